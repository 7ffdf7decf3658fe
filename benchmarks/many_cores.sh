#!/usr/bin/env bash
# Measurements that need a machine with many free cores (at least 8), in one run:
#   1. `impactbar warmup` with an empty numba cache, its default jobs (the cores), then
#   2. the documented multistart search (docs/optimising_a_drifter.md) on 4 workers, warm, then
#   3. if time is left, `impactbar warmup --jobs 1` with another empty cache (the serial baseline).
# Run from the repository's root: `bash benchmarks/many_cores.sh [OUTDIR]`; logs and the search's
# result go to OUTDIR (default: ./many_cores_out). PYTHON names the interpreter (default python3);
# PYTHONPATH must let it import impactbar (e.g. PYTHONPATH=src) and the dependencies.
set -u
out=${1:-many_cores_out}
mkdir -p "$out"
py=${PYTHON:-python3}
export PYTHONUNBUFFERED=1
t0=$(date +%s)
echo "cores: $(nproc)  load: $(cut -d' ' -f1-3 /proc/loadavg)" | tee "$out/machine.txt"
"$py" -c "import sys, numpy, scipy, numba, dask, distributed, impactbar; print(sys.version.split()[0], 'numpy', numpy.__version__, 'scipy', scipy.__version__, 'numba', numba.__version__, 'dask', dask.__version__, 'impactbar', impactbar.__version__)" | tee "$out/versions.txt"
[ "${PIPESTATUS[0]}" = 0 ] || exit 4

cache_a=$(mktemp -d)
echo "== warmup, default jobs, empty cache $cache_a"
TIMEFORMAT="warmup, default jobs: wall %R s, user %U s, sys %S s"
time (NUMBA_CACHE_DIR=$cache_a "$py" -m impactbar warmup 2>&1 | tee "$out/warmup_jobs.log" | tail -25)
echo "load $(cut -d' ' -f1-3 /proc/loadavg)"

echo "== multistart on 4 workers, the warm cache"
TIMEFORMAT="multistart on 4 workers: wall %R s, this shell's children user %U s, sys %S s"
time (NUMBA_CACHE_DIR=$cache_a "$py" benchmarks/bench_optimize_drifter.py --method multistart --sample 256 \
    --local-starts 3 --max-evaluations 376 --polish ${POLISH:-40} --workers 4 --project 4,8 \
    --out "$out/multistart_4.json" 2>&1 | tee "$out/multistart_4.log" | tail -60)
echo "load $(cut -d' ' -f1-3 /proc/loadavg)"

left=$(( ${BUDGET_S:-520} - ($(date +%s) - t0) ))
if [ "$left" -gt 170 ]; then
    cache_b=$(mktemp -d)
    echo "== warmup --jobs 1, empty cache $cache_b ($left s left)"
    TIMEFORMAT="warmup --jobs 1: wall %R s, user %U s, sys %S s"
    time (NUMBA_CACHE_DIR=$cache_b timeout $((left - 15)) "$py" -m impactbar warmup --jobs 1 2>&1 \
        | tee "$out/warmup_1.log" | tail -8)
else
    echo "== warmup --jobs 1 skipped: $left s left"
fi
echo "total: $(( $(date +%s) - t0 )) s"
