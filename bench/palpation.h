/* softhap_bench palpation: a sphere pressed into the liver held at its base, stepped at 60 Hz with
 * implicit Euler, per material: step cost, Newton and sub-step counts, warnings and the tool force
 * (see palpation.c). */
#ifndef SOFTHAP_BENCH_PALPATION_H
#define SOFTHAP_BENCH_PALPATION_H

/* Runs the palpation cases; argv[0] is "palpation". JSON lines go to stdout, progress to
 * stderr. Returns the process exit code. */
int run_palpation(int argc, char** argv);

#endif
