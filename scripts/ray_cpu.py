#!/usr/bin/env python3
"""The CPU time a local Ray cluster's own processes use while a command runs.

    scripts/ray_cpu.py --out FILE SESSION...             # sample
    scripts/ray_cpu.py --report FILE [--timings T]       # print

Samples, every --interval seconds until SIGTERM or SIGINT, the CPU time
(user + system, /proc/PID/stat) of every process in the given sessions
(the `ray start` commands that scripts/ray_speedup.sh starts with setsid:
their raylet, GCS, agents, log monitor and workers), then writes to FILE
each kind of process's CPU seconds during the sampling (a process that
started meanwhile counts from zero; one that ended counts until its last
sample) as JSON: {"kinds": {kind: seconds}, "seconds": wall}.
--report prints such a file, and with the run's TACTRACE_RAY_TIMINGS
file the share of Ray's own processes (all kinds but the workers) in the
evaluations' CPU time, and the workers' CPU outside their evaluations.
Linux only; no dependencies.
"""

import argparse
import json
import os
import signal
import time

TICK = os.sysconf("SC_CLK_TCK")

#: Process kinds by a piece of their command line, the first match wins.
KINDS = [
    ("gcs_server", "gcs_server"),
    ("raylet", "raylet"),
    ("log_monitor", "log_monitor"),
    ("dashboard/agent.py", "dashboard_agent"),
    ("ray::DashboardAgent", "dashboard_agent"),
    ("runtime_env/agent", "runtime_env_agent"),
    ("ray::RuntimeEnvAgent", "runtime_env_agent"),
    ("autoscaler/_private/monitor", "autoscaler_monitor"),
    ("dashboard/dashboard.py", "dashboard"),
    ("ray::", "worker"),
    ("default_worker.py", "worker"),
    ("ray start", "ray_start"),
    ("bin/ray", "ray_start"),
]


def kind(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            cmd = f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return None
    for piece, name in KINDS:
        if piece in cmd:
            return name
    return os.path.basename(cmd.split(" ", 1)[0]) or "other"


def sample(sessions):
    """{pid: (session, ticks)} of the processes in the sessions."""
    out = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        # after the name: state ppid pgrp session ... utime(12) stime(13)
        if int(fields[3]) in sessions:
            out[int(entry)] = int(fields[11]) + int(fields[12])
    return out


def report(path, timings):
    """Print a sampled file, against the evaluations' CPU of `timings`."""
    with open(path) as f:
        cpu = json.load(f)
    kinds = cpu["kinds"]
    for name, seconds in sorted(kinds.items(), key=lambda kv: -kv[1]):
        print(f"  {name:20s} {seconds:8.2f} s")
    own = sum(v for k, v in kinds.items() if k != "worker")
    line = f"  Ray's own processes (all but the workers): {own:.2f} s CPU in {cpu['seconds']:.1f} s"
    if timings:
        with open(timings) as f:
            evals = sum(json.loads(row).get("eval_cpu", 0) for row in f if row.strip())
        line += f", {100 * own / max(evals, 1e-9):.1f} % of the evaluations' CPU ({evals:.2f} s)"
        print(line)
        print(f"  workers' CPU outside their evaluations (start-up included): {kinds.get('worker', 0) - evals:.2f} s")
    else:
        print(line)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", help="sample into this file")
    parser.add_argument("--interval", type=float, default=0.25)
    parser.add_argument("--report", help="print this sampled file")
    parser.add_argument("--timings", help="with --report: the run's TACTRACE_RAY_TIMINGS file")
    parser.add_argument("sessions", nargs="*", type=int)
    args = parser.parse_args()
    if args.report:
        report(args.report, args.timings)
        return
    if not args.out or not args.sessions:
        parser.error("sampling needs --out and at least one session")
    sessions = set(args.sessions)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    start = time.time()
    first = sample(sessions)
    last, kinds = dict(first), {}
    for pid in first:
        kinds[pid] = kind(pid)
    while not stop:
        time.sleep(args.interval)
        for pid, ticks in sample(sessions).items():
            # Looked at again each time: a worker just forked by its raylet
            # shows the raylet's command line until it runs its own.
            kinds[pid] = kind(pid) or kinds.get(pid)
            first.setdefault(pid, 0)
            last[pid] = ticks
    totals = {}
    for pid, ticks in last.items():
        name = kinds.get(pid) or "other"
        totals[name] = totals.get(name, 0.0) + (ticks - first.get(pid, 0)) / TICK
    with open(args.out, "w") as f:
        json.dump({"kinds": totals, "seconds": time.time() - start}, f)


if __name__ == "__main__":
    main()
