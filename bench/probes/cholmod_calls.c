/* A probe (not part of the build): counts and times the CHOLMOD solves and factorizations of any
 * process, by interposing cholmod_solve and cholmod_factorize.
 *
 *   gcc -O2 -shared -fPIC bench/probes/cholmod_calls.c -o cholmod_calls.so -ldl
 *   LD_PRELOAD=./cholmod_calls.so corrlap regularize ...      # prints one line at exit
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
#include <stdio.h>
#include <time.h>

static double solve_seconds, factorize_seconds;
static int solves, factorizations;
static long columns;

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The leading fields of cholmod_dense (nrow, ncol). */
struct dense_head {
  size_t nrow, ncol;
};

void* cholmod_solve(int sys, void* factor, void* rhs, void* common) {
  static void* (*next)(int, void*, void*, void*);
  if (!next) *(void**)&next = dlsym(RTLD_NEXT, "cholmod_solve");
  const double start = now();
  void* x = next(sys, factor, rhs, common);
  solve_seconds += now() - start;
  ++solves;
  columns += (long)((struct dense_head*)rhs)->ncol;
  return x;
}

int cholmod_factorize(void* matrix, void* factor, void* common) {
  static int (*next)(void*, void*, void*);
  if (!next) *(void**)&next = dlsym(RTLD_NEXT, "cholmod_factorize");
  const double start = now();
  const int ok = next(matrix, factor, common);
  factorize_seconds += now() - start;
  ++factorizations;
  return ok;
}

__attribute__((destructor)) static void report(void) {
  fprintf(stderr, "cholmod_calls: %d solves (%ld columns) %.2f s, %d factorizations %.2f s\n", solves, columns,
          solve_seconds, factorizations, factorize_seconds);
}
