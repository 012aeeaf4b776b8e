/* softhap_bench haptic, haptic-error, haptic-force: the haptic step's cost, its force error
 * against the full model, and the smoothness of the rendered force (see haptic.c). */
#ifndef SOFTHAP_BENCH_HAPTIC_H
#define SOFTHAP_BENCH_HAPTIC_H

/* Runs one haptic study; argv[0] is its subcommand ("haptic", "haptic-error" or
 * "haptic-force"). JSON lines go to stdout, progress to stderr. Returns the exit code. */
int run_haptic(int argc, char** argv);

/* 1 if name is one of run_haptic's subcommands. */
int is_haptic_command(const char* name);

#endif
