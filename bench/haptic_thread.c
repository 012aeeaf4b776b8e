/* The haptic studies' thread helpers: the allocator that counts the haptic thread's allocations
 * (a haptic step must make none), CPU pinning, SCHED_FIFO and absolute-deadline sleeps. */
#define _GNU_SOURCE
#include "haptic_common.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef __linux__
#include <sched.h>
#endif

/* Counting is per thread, so that the sim thread's allocations (it re-extracts buffers) are not
 * charged to the haptic thread. */
static _Thread_local int tl_counting;
static atomic_long g_allocations;

/* sh_allocator's alloc: posix_memalign, counted while the calling thread counts. */
static void* counting_alloc(size_t size, size_t alignment, void* user) {
    (void)user;
    if (tl_counting) atomic_fetch_add(&g_allocations, 1);
    void* p = NULL;
    return posix_memalign(&p, alignment < sizeof(void*) ? sizeof(void*) : alignment, size ? size : 1) == 0 ? p : NULL;
}

/* sh_allocator's free: free, counted (a free of NULL is not) while the calling thread counts. */
static void counting_free(void* ptr, void* user) {
    (void)user;
    if (ptr && tl_counting) atomic_fetch_add(&g_allocations, 1);
    free(ptr);
}

void install_counting_allocator(void) {
    const sh_allocator allocator = {counting_alloc, counting_free, NULL};
    CHECK(sh_set_allocator(&allocator));
}

void remove_counting_allocator(void) { CHECK(sh_set_allocator(NULL)); }

void alloc_count_on(void) {
    atomic_store(&g_allocations, 0);
    tl_counting = 1;
}

long alloc_count_off(void) {
    tl_counting = 0;
    return atomic_load(&g_allocations);
}

void choose_cpus(haptic_options* options) {
    options->haptic_cpu = bench_current_cpu();
    options->sim_cpu = -1;
#ifdef __linux__
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0)
        for (int c = 0; c < CPU_SETSIZE && options->sim_cpu < 0; ++c)
            if (c != options->haptic_cpu && CPU_ISSET(c, &set)) options->sim_cpu = c;
#endif
    if (options->sim_cpu < 0) options->sim_cpu = options->haptic_cpu;
    bench_pin_thread(options->haptic_cpu);
}

int make_realtime(void) {
    struct sched_param rt;
    memset(&rt, 0, sizeof rt);
    rt.sched_priority = 10;
    return pthread_setschedparam(pthread_self(), SCHED_FIFO, &rt) == 0;
}

void make_ordinary(void) {
    struct sched_param normal;
    memset(&normal, 0, sizeof normal);
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
}

void sleep_until(double deadline_ns) {
    struct timespec t;
    t.tv_sec = (time_t)(deadline_ns * 1e-9);
    t.tv_nsec = (long)(deadline_ns - (double)t.tv_sec * 1e9);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, NULL) != 0) {
    }
}
