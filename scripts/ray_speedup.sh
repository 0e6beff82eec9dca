#!/usr/bin/env bash
# The Ray executor's speed on this machine: one search batch of B trials
# (all drawn together: --startup B --batch B) run by
#   1. the local executor on 1 thread (RAYON_NUM_THREADS=1),
#   2. a local Ray cluster of 1 worker node of 1 CPU,
#   3. the same cluster with a second worker node of 1 CPU,
# then the 2-worker speed-up (batch time with 1 worker / with 2) and the
# overhead per evaluation (Ray with 1 worker against the local thread, the
# same B evaluations one after another, as a share of one evaluation's
# time). It checks that the three searches gave the same trials.
#
# Then where the overhead goes, for each Ray run: the driver's timings of
# every call to a worker (TACTRACE_RAY_TIMINGS, summed by
# `python -m tactrace.ray_timings`: dispatch, start-up, evaluations,
# return, the workers' CPU share while evaluating) and the CPU time of
# Ray's own processes during the run (scripts/ray_cpu.py: raylet, GCS,
# agents, ...), beside the local run's CPU time.
#
# The nodes start lean (docs/search.md, "Starting the nodes lean"): no
# dashboard, log monitor, autoscaler monitor, metrics, task events, event
# statistics, memory monitor or usage stats; workers at nice 0. --plain
# starts them as Ray does by default (workers still at nice 0), to compare.
#
# Meant for an otherwise idle machine with at least 2 cores: under load the
# wall times measure the load (the CPU times less so). It starts and stops
# its own Ray nodes (by process group, on a free port of 127.0.0.1), never
# `ray stop`.
#
# Needs target/release/tactrace (cargo build --release) and the venv of
# scripts/test.sh (target/py-venv, with ray and the tactrace package:
# run scripts/test.sh once). TACTRACE_PYTHON picks another interpreter
# with both.
#
#   scripts/ray_speedup.sh            # B = 8 trials, PDenNN, 300 epochs, 1500 taps
#   scripts/ray_speedup.sh --tiny     # B = 2, 2 epochs, 200 taps: checks it runs (seconds)
#   scripts/ray_speedup.sh --trials 16 --epochs 600 --samples 3000 --keep DIR
#   scripts/ray_speedup.sh --plain    # the nodes with Ray's defaults
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

trials=8 epochs=300 samples=1500 keep="" plain=""
while [ $# -gt 0 ]; do
    case $1 in
        --tiny) trials=2 epochs=2 samples=200 ;;
        --trials) trials=$2; shift ;;
        --epochs) epochs=$2; shift ;;
        --samples) samples=$2; shift ;;
        --keep) keep=$2; shift ;;
        --plain) plain=1 ;;
        -h|--help) sed -n '2,40p' "$0"; exit 0 ;;
        *) echo "unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
    shift
done

T=$root/target/release/tactrace
python=${TACTRACE_PYTHON:-$root/target/py-venv/bin/python}
ray=$(dirname "$python")/ray
[ -x "$T" ] || { echo "no $T: cargo build --release first" >&2; exit 2; }
[ -x "$ray" ] || { echo "no $ray: run scripts/test.sh once (its venv has ray)" >&2; exit 2; }
"$python" -c "import ray, tactrace" || {
    echo "$python lacks ray or the tactrace package: run scripts/test.sh once" >&2; exit 2; }

work=${keep:-$(mktemp -d /tmp/ray-speedup.XXXXXX)}
mkdir -p "$work"
nodes=()
cleanup() {
    for pid in "${nodes[@]}"; do
        kill -TERM -- "-$pid" 2>/dev/null || true
    done
    for pid in "${nodes[@]}"; do
        for _ in $(seq 30); do kill -0 "$pid" 2>/dev/null || break; sleep 1; done
        kill -KILL -- "-$pid" 2>/dev/null || true
    done
    [ -n "$keep" ] || rm -rf "$work"
}
trap cleanup EXIT

port=$("$python" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
address=127.0.0.1:$port
export RAY_USAGE_STATS_ENABLED=0
# Ray starts its worker processes at nice 15 (its `worker_niceness`):
# they would give way to every other process, Ray's own included, and the
# comparison with the command's own thread (nice 0) would measure that.
# The nodes here start their workers at the command's priority.
export RAY_worker_niceness=0
lean=() head_lean=()
if [ -z "$plain" ]; then
    # Lean nodes: no metrics recorded or exported, no task events sent to
    # the GCS, no per-event statistics in the event loops, no memory
    # monitor (it reads /proc 4 times a second; it also kills workers
    # when memory runs short), no log monitor; on the head no autoscaler
    # monitor (nothing to scale here).
    export RAY_enable_metrics_collection=0 RAY_task_events_report_interval_ms=0 \
        RAY_event_stats=0 RAY_memory_monitor_refresh_ms=0
    lean=(--include-log-monitor=false)
    head_lean=(--no-monitor)
fi

# A Ray node in its own process group and session (stopped with its
# raylet and GCS; its processes' CPU found by session).
start_node() {
    local log=$1; shift
    setsid "$ray" start --block --num-cpus 1 --disable-usage-stats \
        --node-ip-address 127.0.0.1 "${lean[@]}" "$@" >"$log" 2>&1 &
    nodes+=($!)
}

# Wait until the cluster has $1 live nodes.
wait_nodes() {
    local code="import ray; ray.init(address='$address', logging_level='ERROR'); print(sum(1 for n in ray.nodes() if n['Alive']))"
    for _ in $(seq 120); do
        if [ "$("$python" -c "$code" 2>/dev/null | tail -n 1)" = "$1" ]; then return 0; fi
        sleep 1
    done
    echo "the local Ray cluster did not reach $1 nodes; logs in $work" >&2
    keep=$work
    exit 1
}

cd "$work"
"$T" collect --samples "$samples" --seed 3 --out ds >/dev/null
space=$root/configs/search/pdennn.toml
args=(search --train ds --space "$space" --trials "$trials" --batch "$trials"
      --startup "$trials" --epochs "$epochs" --seed 4)

# The batch's wall time: trials.csv's seconds a trial (the batch's time
# shared among its trials) times the trials.
batch_seconds() {
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "seconds") c = i; next }
             { s += $c } END { printf "%.3f", s }' "$1/trials.csv"
}

# The command's wall and CPU time (a Ray worker's CPU is spent in the
# nodes' processes, not counted here: ray_cpu.py counts it).
TIMEFORMAT='%R s wall, %U s user + %S s sys'
echo "== local executor, 1 thread"
{ time (RAYON_NUM_THREADS=1 "$T" "${args[@]}" --out local1 >local1.log 2>&1) \
    || { cat local1.log >&2; exit 1; }; } 2>local1.time
cat local1.time

# A search on the cluster, its calls timed (ray_timings) and the CPU of
# the nodes' processes sampled meanwhile (ray_cpu.py).
ray_run() {
    local out=$1
    "$python" "$root/scripts/ray_cpu.py" --out "$out.cpu.json" "${nodes[@]}" &
    local sampler=$!
    sleep 0.5
    time (TACTRACE_RAY_TIMINGS=$work/$out.timings.jsonl "$T" "${args[@]}" --executor ray \
        --ray-address "$address" --python "$python" --out "$out" >"$out.log" 2>&1) \
        || { kill "$sampler"; cat "$out.log" >&2; exit 1; }
    kill -TERM "$sampler"
    wait "$sampler" || true
}

start_node head.log --head --port "$port" --include-dashboard=false "${head_lean[@]}"
wait_nodes 1
echo "== Ray, 1 worker node of 1 CPU"
ray_run ray1

start_node worker.log --address "$address"
wait_nodes 2
echo "== Ray, 2 worker nodes of 1 CPU"
ray_run ray2

same=yes
for d in ray1 ray2; do
    "$python" - local1 "$d" <<'EOF' || same=no
import json, sys
def rows(d):
    out = []
    for line in open(f"{d}/trials.jsonl"):
        r = json.loads(line); r.pop("seconds"); out.append(r)
    return out
sys.exit(0 if rows(sys.argv[1]) == rows(sys.argv[2]) else 1)
EOF
done

local1=$(batch_seconds local1) ray1=$(batch_seconds ray1) ray2=$(batch_seconds ray2)
echo
echo "batch of $trials trials ($epochs epochs, $samples taps), wall seconds:"
echo "  local, 1 thread:        $local1 s"
echo "  Ray, 1 worker of 1 CPU: $ray1 s"
echo "  Ray, 2 workers:         $ray2 s"
awk -v l="$local1" -v r1="$ray1" -v r2="$ray2" -v n="$trials" 'BEGIN {
    printf "speed-up, 2 workers against 1: %.2fx (goal >= 1.8x)\n", r1 / r2
    printf "overhead per evaluation: %.3f s, %.1f %% of an evaluation (%.3f s; goal < 5 %%)\n",
        (r1 - l) / n, 100 * (r1 - l) / l, l / n
}'
echo "trials equal to the local executor's: $same"
echo
echo "where the time went ($([ -n "$plain" ] && echo "nodes with Ray's defaults" || echo lean nodes)):"
echo "-- local1: the command's CPU (1 thread): $(cat local1.time)"
for d in ray1 ray2; do
    echo "-- $d: the calls to the workers (tactrace.ray_timings)"
    "$python" -m tactrace.ray_timings "$d.timings.jsonl"
    echo "-- $d: CPU of the nodes' processes during the run (scripts/ray_cpu.py)"
    "$python" "$root/scripts/ray_cpu.py" --report "$d.cpu.json" --timings "$d.timings.jsonl"
done
echo "load average now: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
[ "$same" = yes ]
