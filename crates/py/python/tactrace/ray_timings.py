"""Where a Ray run's time went: ``python -m tactrace.ray_timings FILE``.

FILE is what the Ray executor's driver wrote under
``TACTRACE_RAY_TIMINGS=FILE`` (``tactrace.ray_executor``): one JSON line per
call to a worker (a chunk of a batch's configurations) with its times
(seconds since the epoch, one clock when the workers share the driver's
machine) and the worker process's CPU seconds, and a last line with the
driver's CPU seconds. Per call:

  sent -> start    dispatch: the driver's call reaching the worker
  start -> ready   start-up: the evaluation built (its data read; only the
                   first call of a worker and context builds)
  ready -> end     the evaluations themselves
  end -> got       return: the results back in the driver

The summary adds these up; "overhead per evaluation" is the round trip
(sent -> got) less the evaluations, shared among the configurations, and
"CPU share" the worker's CPU seconds over its wall seconds while
evaluating (below 1: the worker waited for a core, or for something else).
"""

import argparse
import json
import sys
from collections import defaultdict


def read(path):
    """The calls and the driver's CPU seconds (None if not written)."""
    calls, driver_cpu = [], None
    with open(path) as f:
        for line in f:
            if not line.strip():
                continue
            row = json.loads(line)
            if "driver_cpu" in row:
                driver_cpu = row["driver_cpu"]
            else:
                calls.append(row)
    return calls, driver_cpu


def summarise(calls, driver_cpu=None):
    """The sums of a run's calls (seconds), as a dict."""
    n = sum(c["configs"] for c in calls)
    s = {
        "calls": len(calls),
        "evaluations": n,
        "workers": len({c["worker"] for c in calls}),
        "built": sum(1 for c in calls if c["built"]),
        "dispatch": sum(c["start"] - c["sent"] for c in calls),
        "startup": sum(c["ready"] - c["start"] for c in calls),
        "startup_cpu": sum(c["prepare_cpu"] for c in calls),
        "evaluation": sum(c["end"] - c["ready"] for c in calls),
        "evaluation_cpu": sum(c["eval_cpu"] for c in calls),
        "return": sum(c["got"] - c["end"] for c in calls),
        "round_trip": sum(c["got"] - c["sent"] for c in calls),
        "idle": _idle(calls),
        "driver_cpu": driver_cpu,
    }
    s["overhead"] = s["round_trip"] - s["evaluation"]
    return s


def _idle(calls):
    """The workers' time between the end of one call and the start of
    their next (within a batch)."""
    by_worker = defaultdict(list)
    for c in calls:
        by_worker[(c["worker"], c["batch"])].append(c)
    idle = 0.0
    for cs in by_worker.values():
        cs.sort(key=lambda c: c["start"])
        idle += sum(b["start"] - a["end"] for a, b in zip(cs, cs[1:]))
    return idle


def report(s):
    """The summary as lines of text."""
    n = max(1, s["evaluations"])
    per_eval = s["evaluation"] / n
    share = (lambda x: 100 * x / s["evaluation"]) if s["evaluation"] > 0 else (lambda x: 0.0)
    lines = [
        f"{s['evaluations']} evaluations in {s['calls']} calls on {s['workers']} workers "
        f"({s['built']} builds)",
        f"  evaluations:  {s['evaluation']:.3f} s wall, {s['evaluation_cpu']:.3f} s CPU "
        f"(CPU share {s['evaluation_cpu'] / max(s['evaluation'], 1e-9):.3f}), "
        f"{per_eval:.3f} s an evaluation",
        f"  start-up:     {s['startup']:.3f} s wall, {s['startup_cpu']:.3f} s CPU "
        f"({share(s['startup']):.2f} %)",
        f"  dispatch:     {s['dispatch']:.3f} s ({share(s['dispatch']):.2f} %)",
        f"  return:       {s['return']:.3f} s ({share(s['return']):.2f} %)",
        f"  overhead per evaluation (round trip less evaluation): "
        f"{s['overhead'] / n:.4f} s, {share(s['overhead']):.2f} % of an evaluation",
        f"  workers idle between calls: {s['idle']:.3f} s",
    ]
    if s["driver_cpu"] is not None:
        lines.append(f"  driver CPU: {s['driver_cpu']:.3f} s")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m tactrace.ray_timings")
    parser.add_argument("file", help="the TACTRACE_RAY_TIMINGS file of a run")
    parser.add_argument("--json", action="store_true", help="the sums as one JSON object")
    args = parser.parse_args(argv)
    calls, driver_cpu = read(args.file)
    if not calls:
        print(f"{args.file} holds no call", file=sys.stderr)
        return 2
    s = summarise(calls, driver_cpu)
    print(json.dumps(s) if args.json else "\n".join(report(s)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
