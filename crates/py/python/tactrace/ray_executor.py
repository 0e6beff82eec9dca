"""The Ray executor's driver: ``python -m tactrace.ray_executor --address A``.

Started by ``tactrace search|sim-fit|tune --executor ray``. It joins the
Ray cluster at the address (``ray.init``), starts one worker (a Ray actor,
``_Worker``) per ``--cpus-per-task`` CPUs of the cluster, says so on one
JSON line, then reads one batch per line from standard input and answers
each with one line: the scores in order, or the failure.

A worker is a process kept for the driver's life: it builds an evaluation
once (``tactrace._tactrace.prepare``: the data read once per worker and
context) and then evaluates configuration after configuration
(``tactrace._tactrace.evaluate``, the same Rust evaluation the command runs
locally). The driver hands each free worker the next chunk of the batch
(one configuration, or a few when the batch is much larger than the
workers), so a slow evaluation holds up no other.

Configurations, contexts and scores are JSON *text* that this module never
parses, so no float is rounded on the way. Paths in a context are the
command's: each call first changes to the command's working directory,
which every worker must see (a shared file system, as on Slurm).

With ``TACTRACE_RAY_TIMINGS=FILE`` in its environment the driver appends
one JSON line per call to FILE: when it was sent, started, ready (the
evaluation built), ended and received, and the worker's CPU time
(``tactrace.ray_timings`` sums them up).

Protocol (one JSON object a line):
  out  {"ready": {"nodes": N, "cpus": C, "workers": W}}
  in   {"name": ..., "context": ..., "cwd": ..., "configs": [text, ...]}
  out  {"scores": [text, ...]}
  out  {"error": {"kind": "setup"|"unreachable"|"evaluation",
                  "message": ..., "bad_input": bool}}
"""

import argparse
import json
import os
import socket
import sys
import time

#: How long workers may take to start before the driver goes on without
#: them (seconds).
START_TIMEOUT = 120.0

#: Chunks per worker a batch is cut into at least: a batch of many short
#: evaluations goes a few at a time (fewer round trips), a batch of a few
#: per worker one at a time (a slow one holds up no other).
CHUNKS_PER_WORKER = 4


class _Worker:
    """One Ray worker process, kept: evaluations built once, run many times.

    It trains on as many threads as it asked CPUs: set before the package
    first runs anything in this process (rayon reads it once), whatever the
    node's environment held (a job's RAYON_NUM_THREADS would otherwise put
    many threads on one CPU)."""

    def __init__(self, threads):
        os.environ["RAYON_NUM_THREADS"] = str(threads)
        from tactrace import _tactrace

        self._tactrace = _tactrace
        self._where = f"{socket.gethostname()}:{os.getpid()}"

    def ready(self):
        return self._where

    def run(self, name, context, cwd, configs):
        """The results of a chunk, each ("ok", score) or (kind, message),
        and the call's timing."""
        start, cpu0 = time.time(), time.process_time()
        if cwd and os.path.isdir(cwd):
            os.chdir(cwd)
        t = self._tactrace
        results, built = [], False
        try:
            built = t.prepare(name, context)
        except t.InputError as e:
            results = [("input", str(e))]
        except Exception as e:  # a failed run, or anything the worker met
            results = [("failed", f"{type(e).__name__}: {e}")]
        ready, cpu1 = time.time(), time.process_time()
        for config in configs if not results else []:
            try:
                results.append(("ok", t.evaluate(name, context, config)))
            except t.InputError as e:
                results.append(("input", str(e)))
                break
            except Exception as e:
                results.append(("failed", f"{type(e).__name__}: {e}"))
                break
        timing = {"worker": self._where, "start": start, "ready": ready, "end": time.time(),
                  "built": built, "prepare_cpu": cpu1 - cpu0,
                  "eval_cpu": time.process_time() - cpu1}
        return results, timing


def _say(out, obj):
    out.write(json.dumps(obj) + "\n")
    out.flush()


def _error(kind, message, bad_input=False):
    return {"error": {"kind": kind, "message": message, "bad_input": bad_input}}


def _unreachable(address):
    """Why a HOST:PORT address cannot be reached now, or None (``ray.init``
    would wait for minutes before saying so)."""
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit():
        return None
    try:
        socket.create_connection((host, int(port)), timeout=5).close()
    except OSError as e:
        return f"nothing answers at {address} ({e})"
    return None


class _Pool:
    """The driver's workers: one per `cpus` CPUs of the cluster, started
    (again) when the cluster has grown."""

    def __init__(self, ray, cpus):
        self.ray, self.cpus, self.workers = ray, cpus, []
        self.why = f"the cluster has fewer than {cpus} CPUs free"
        self.seen_cpus = None
        self.actor = ray.remote(_Worker).options(num_cpus=cpus, max_restarts=0,
                                                  max_task_retries=0)

    def grow(self):
        """Start workers for the cluster's CPUs not yet used (once per size
        of the cluster: workers that found no room are not tried again
        until it changes); how many run."""
        total = self.ray.cluster_resources().get("CPU", 0)
        if total == self.seen_cpus:
            return len(self.workers)
        self.seen_cpus = total
        wanted = int(total // self.cpus)
        new = [self.actor.remote(self.cpus) for _ in range(max(0, wanted - len(self.workers)))]
        if new:
            refs = {w.ready.remote(): w for w in new}
            ready, late = self.ray.wait(list(refs), num_returns=len(refs), timeout=START_TIMEOUT)
            for ref in late:  # no room for it now (CPUs taken by others)
                self.ray.kill(refs[ref])
            for ref in ready:
                try:
                    self.ray.get(ref)
                    self.workers.append(refs[ref])
                except Exception as e:  # a worker that cannot import tactrace
                    self.why = f"{type(e).__name__}: {e}"
                    print(f"a Ray worker did not start: {self.why}", file=sys.stderr)
        return len(self.workers)


def chunks(count, workers):
    """The batch's indices cut into chunks: one configuration each unless
    the batch has more than CHUNKS_PER_WORKER per worker."""
    size = max(1, count // (max(1, workers) * CHUNKS_PER_WORKER))
    return [list(range(i, min(count, i + size))) for i in range(0, count, size)]


class _Timings:
    """Where the calls' timings go (TACTRACE_RAY_TIMINGS), if anywhere."""

    def __init__(self, path):
        self.file = open(path, "a") if path else None
        self.batch = 0

    def add(self, sent, got, count, timing):
        if self.file:
            row = dict(timing, batch=self.batch, configs=count, sent=sent, got=got)
            self.file.write(json.dumps(row) + "\n")

    def close(self):
        if self.file:
            self.file.write(json.dumps({"driver_cpu": time.process_time()}) + "\n")
            self.file.close()


def _run_batch(ray, pool, request, timings):
    """The scores of one batch, in order, or its failure."""
    name, context, cwd = request["name"], request["context"], request.get("cwd")
    configs = request["configs"]
    timings.batch += 1
    if not pool.grow():
        return _error("evaluation", f"no Ray worker could start on the cluster: {pool.why}")
    context_ref = ray.put(context)
    todo = chunks(len(configs), len(pool.workers))
    todo.reverse()
    free, running, results = list(pool.workers), {}, [None] * len(configs)
    while todo or running:
        while free and todo:
            worker, part, sent = free.pop(), todo.pop(), time.time()
            ref = worker.run.remote(name, context_ref, cwd, [configs[i] for i in part])
            running[ref] = (worker, part, sent)
        done, _ = ray.wait(list(running), num_returns=1)
        worker, part, sent = running.pop(done[0])
        try:
            got, timing = ray.get(done[0])
        except Exception as e:  # a lost worker or node
            return _error("evaluation", f"a Ray worker failed: {type(e).__name__}: {e}")
        timings.add(sent, time.time(), len(part), timing)
        for i, (kind, value) in zip(part, got):
            if kind != "ok":
                return _error("evaluation", value, bad_input=(kind == "input"))
            results[i] = value
        free.append(worker)
    return {"scores": results}


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m tactrace.ray_executor")
    parser.add_argument("--address", default="auto", help="the Ray cluster (HOST:PORT or auto)")
    parser.add_argument("--cpus-per-task", type=int, default=1,
                        help="CPUs each worker asks for (and rayon threads it uses)")
    args = parser.parse_args(argv)
    # The protocol keeps the real standard output; anything else printed
    # (by Ray, by a library) goes to standard error.
    out = os.fdopen(os.dup(sys.stdout.fileno()), "w")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    try:
        import ray
    except ImportError as e:
        _say(out, _error("setup", f"cannot import ray ({e})", bad_input=True))
        return 2
    why = _unreachable(args.address)
    if why:
        _say(out, _error("unreachable", why))
        return 1
    try:
        ray.init(address=args.address, log_to_driver=False, logging_level="ERROR")
    except Exception as e:
        _say(out, _error("unreachable", f"{type(e).__name__}: {e}"))
        return 1
    pool = _Pool(ray, args.cpus_per_task)
    workers = pool.grow()
    resources = ray.cluster_resources()
    _say(out, {"ready": {"nodes": len([n for n in ray.nodes() if n.get("Alive")]),
                         "cpus": resources.get("CPU", 0), "workers": workers}})
    timings = _Timings(os.environ.get("TACTRACE_RAY_TIMINGS"))
    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            request = json.loads(line)
        except json.JSONDecodeError as e:
            _say(out, _error("protocol", f"a request that is not JSON: {e}"))
            continue
        _say(out, _run_batch(ray, pool, request, timings))
    timings.close()
    ray.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
