/* softhap_bench accuracy: error against run time (see accuracy.c). */
#ifndef SOFTHAP_BENCH_ACCURACY_H
#define SOFTHAP_BENCH_ACCURACY_H

/* Runs the accuracy studies; argv[0] is "accuracy". JSON lines go to stdout, progress to
 * stderr. Returns the process exit code. */
int run_accuracy(int argc, char** argv);

#endif
