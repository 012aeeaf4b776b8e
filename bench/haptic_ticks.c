/* Timed runs of haptic ticks, as a device loop makes them, and the step times' JSON fields. */
#include "haptic_common.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void tick_log_alloc(tick_log* log, int count) {
    memset(log, 0, sizeof *log);
    log->ns = (double*)xmalloc(sizeof(double) * (size_t)count);
    log->substeps = (double*)xmalloc(sizeof(double) * (size_t)count);
}

void tick_log_free(tick_log* log) {
    free(log->ns);
    free(log->substeps);
}

/* Adds one tick's output (and its time t_ns, if the log keeps times) to the log. */
static void log_tick(tick_log* log, sh_status status, const sh_haptic_output* out, double dt, double t_ns) {
    if (status != SH_OK) log->faults |= 0x80000000u;
    if (log->ns) {
        log->ns[log->timed] = t_ns;
        log->substeps[log->timed] = out->substeps;
        ++log->timed;
    }
    log->contact += out->contact;
    log->fresh += out->data_age <= dt * 1.000001; /* the buffer adopted at this tick */
    log->faults |= out->faults;
}

void run_ticks(sh_haptic* haptic, path_fn path, const void* ctx, long first, long count, double dt, int paced,
               tick_log* log) {
    double deadline = now_ns();
    sh_haptic_output out;
    memset(&out, 0, sizeof out);
    const int counting = log->ns != NULL;
    if (counting) alloc_count_on();
    for (long i = 0; i < count; ++i) {
        double p[3];
        path(ctx, first + i, p);
        if (paced) {
            deadline += dt * 1e9;
            sleep_until(deadline);
        }
        const double t0 = now_ns();
        const sh_status st = sh_haptic_step(haptic, p, kIdentity, dt, &out);
        const double t1 = now_ns();
        log_tick(log, st, &out, dt, t1 - t0);
    }
    if (counting) log->allocations += alloc_count_off();
    log->last = out;
}

void print_times_us(const char* prefix, const stats* s) {
    printf("\"%smedian_us\":%.3f,\"%sp99_us\":%.3f,\"%sp999_us\":%.3f,\"%smax_us\":%.3f,\"%smean_us\":%.3f", prefix,
           s->median * 1e-3, prefix, s->p99 * 1e-3, prefix, s->p999 * 1e-3, prefix, s->max * 1e-3, prefix,
           s->mean * 1e-3);
}
