#!/usr/bin/env python3
"""Interleaved faer vs CHOLMOD timing: compare.py MATRIX.mtx ROUNDS RUNS (paths: see B and C)."""
import json, subprocess, statistics, sys, os
HERE = os.path.dirname(os.path.abspath(__file__))
B = os.environ.get("FAER_BENCH", os.path.join(HERE, "../../../target/release/examples/bench"))
C = os.path.join(HERE, "cholmod_bench")
env=dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", LD_LIBRARY_PATH="/usr/lib/x86_64-linux-gnu/openblas-serial")
def run(cmd):
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, env=env).stdout.strip().splitlines()[-1])
mtx, rounds, runs = sys.argv[1], int(sys.argv[2]), sys.argv[3]
F, Cm = [], []
for r in range(rounds):
    order = [0,1] if r % 2 == 0 else [1,0]
    for o in order:
        if o == 0: F.append(run([B,"solve",mtx,"--runs",runs]))
        else: Cm.append(run([C,mtx,runs]))
out = {"matrix": os.path.basename(mtx), "n": F[0]["n"], "nnz": F[0]["nnz"], "rounds": rounds, "runs_per_round": int(runs)}
for k in ["analyze_ms","factor_ms","solve_ms"]:
    f = statistics.median(x[k] for x in F); c = statistics.median(x[k] for x in Cm)
    ratios = [a[k]/b[k] for a,b in zip(F,Cm)]
    out[k] = {"faer": round(f,1), "cholmod": round(c,1), "ratio_of_medians": round(f/c,2), "median_ratio": round(statistics.median(ratios),2), "max_ratio": round(max(ratios),2)}
print(json.dumps(out))
