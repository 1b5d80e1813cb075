/* CHOLMOD reference timings for `fires bench solve` (fires-recon, issue 6).
 *
 * Reads a symmetric positive-definite Matrix Market file (coordinate real symmetric),
 * then times, `runs` times, cholmod_analyze / cholmod_factorize / cholmod_solve with three
 * right-hand sides, and prints the medians as one JSON line with the same fields as
 * fires_recon::bench::SolveTimings. Supernodal factorisation, AMD ordering only (the
 * ordering faer uses) unless `--ordering default` is given. Run single-threaded:
 * OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 (see the Makefile's `run` target).
 *
 * usage: cholmod_bench MATRIX.mtx [runs] [--ordering amd|default]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <suitesparse/cholmod.h>

static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n) {
    qsort(v, n, sizeof(double), cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s MATRIX.mtx [runs] [--ordering amd|default]\n", argv[0]);
        return 2;
    }
    int runs = 5, amd_only = 1;
    for (int i = 2; i < argc; i++) {
        if (strcmp(argv[i], "--ordering") == 0 && i + 1 < argc) {
            amd_only = strcmp(argv[++i], "default") != 0;
        } else {
            runs = atoi(argv[i]);
        }
    }
    if (runs < 1) runs = 1;
    FILE *f = fopen(argv[1], "r");
    if (!f) { perror(argv[1]); return 1; }
    cholmod_common c;
    cholmod_start(&c);
    c.supernodal = CHOLMOD_SUPERNODAL;
    if (amd_only) {
        c.nmethods = 1;
        c.method[0].ordering = CHOLMOD_AMD;
        c.postorder = 1;
    }
    cholmod_sparse *A = cholmod_read_sparse(f, &c);
    fclose(f);
    if (!A || A->stype == 0) { fprintf(stderr, "need a symmetric matrix\n"); return 1; }
    size_t n = A->nrow;
    cholmod_dense *B = cholmod_allocate_dense(n, 3, n, CHOLMOD_REAL, &c);
    double *b = (double *)B->x;
    for (size_t j = 0; j < 3; j++)
        for (size_t i = 0; i < n; i++) b[j * n + i] = 1.0 + (double)((i * (j + 3)) % 17);
    double *ta = malloc(runs * sizeof(double)), *tf = malloc(runs * sizeof(double)), *ts = malloc(runs * sizeof(double));
    double lnz = 0;
    for (int r = 0; r < runs; r++) {
        double t0 = now_ms();
        cholmod_factor *L = cholmod_analyze(A, &c);
        double t1 = now_ms();
        if (!cholmod_factorize(A, L, &c) || c.status != CHOLMOD_OK) {
            fprintf(stderr, "factorisation failed (status %d): not positive definite?\n", c.status);
            return 1;
        }
        double t2 = now_ms();
        cholmod_dense *X = cholmod_solve(CHOLMOD_A, L, B, &c);
        double t3 = now_ms();
        ta[r] = t1 - t0; tf[r] = t2 - t1; ts[r] = t3 - t2;
        lnz = c.lnz;
        cholmod_free_dense(&X, &c);
        cholmod_free_factor(&L, &c);
    }
    printf("{\"n\":%zu,\"nnz\":%ld,\"l_nnz\":%.0f,\"analyze_ms\":%.3f,\"factor_ms\":%.3f,\"solve_ms\":%.3f,\"runs\":%d,\"threads\":1,\"solver\":\"cholmod-supernodal-%s\"}\n",
           n, (long)cholmod_nnz(A, &c), lnz, median(ta, runs), median(tf, runs), median(ts, runs), runs,
           amd_only ? "amd" : "default");
    cholmod_free_dense(&B, &c);
    cholmod_free_sparse(&A, &c);
    cholmod_finish(&c);
    free(ta); free(tf); free(ts);
    return 0;
}
