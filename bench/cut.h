/* softhap_bench cut: the cost of sh_body_cut against body size and cut length, and of the
 * implicit step right after a cut (see cut.c). */
#ifndef SOFTHAP_BENCH_CUT_H
#define SOFTHAP_BENCH_CUT_H

/* Runs the cut study; argv[0] is "cut". JSON lines go to stdout, progress to stderr. Returns the
 * process exit code. */
int run_cut(int argc, char** argv);

#endif
