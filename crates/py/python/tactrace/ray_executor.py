"""The Ray executor's driver: ``python -m tactrace.ray_executor --address A``.

Started by ``tactrace search|sim-fit|tune --executor ray``. It joins the
Ray cluster at the address (``ray.init``), says so on one JSON line, then
reads one batch per line from standard input and answers each with one
line: the scores in order, or the failure. Each configuration of a batch
is one Ray task, which calls ``tactrace._tactrace.evaluate`` (the same Rust
evaluation the command runs locally) in a worker process.

Configurations, contexts and scores are JSON *text* that this module never
parses, so no float is rounded on the way. Paths in a context are the
command's: each task first changes to the command's working directory,
which every worker must see (a shared file system, as on Slurm).

Protocol (one JSON object a line):
  out  {"ready": {"nodes": N, "cpus": C}}
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


def _evaluate(name, context, config, cwd, threads):
    """One evaluation in a Ray worker: ("ok", score) or (kind, message).

    The worker trains on as many threads as the task asked CPUs: set before
    the package first runs anything in this process (rayon reads it once),
    whatever the node's environment held (a job's RAYON_NUM_THREADS would
    otherwise put many threads on one CPU)."""
    os.environ["RAYON_NUM_THREADS"] = str(threads)
    if cwd and os.path.isdir(cwd):
        os.chdir(cwd)
    from tactrace import _tactrace

    try:
        return ("ok", _tactrace.evaluate(name, context, config))
    except _tactrace.InputError as e:
        return ("input", str(e))
    except Exception as e:  # a failed run, or anything the worker met
        return ("failed", f"{type(e).__name__}: {e}")


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


def _run_batch(ray, task, request, threads):
    """The scores of one batch, in order, or its failure."""
    name, context, cwd = request["name"], request["context"], request.get("cwd")
    context_ref = ray.put(context)
    refs = [task.remote(name, context_ref, c, cwd, threads) for c in request["configs"]]
    try:
        results = ray.get(refs)
    except Exception as e:  # a lost worker or node
        return _error("evaluation", f"a Ray task failed: {type(e).__name__}: {e}")
    scores = []
    for kind, value in results:
        if kind != "ok":
            return _error("evaluation", value, bad_input=(kind == "input"))
        scores.append(value)
    return {"scores": scores}


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m tactrace.ray_executor")
    parser.add_argument("--address", default="auto", help="the Ray cluster (HOST:PORT or auto)")
    parser.add_argument("--cpus-per-task", type=int, default=1,
                        help="CPUs each task asks for (and rayon threads it uses)")
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
    task = ray.remote(_evaluate).options(num_cpus=args.cpus_per_task, max_retries=0)
    resources = ray.cluster_resources()
    _say(out, {"ready": {"nodes": len([n for n in ray.nodes() if n.get("Alive")]),
                         "cpus": resources.get("CPU", 0)}})
    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            request = json.loads(line)
        except json.JSONDecodeError as e:
            _say(out, _error("protocol", f"a request that is not JSON: {e}"))
            continue
        _say(out, _run_batch(ray, task, request, args.cpus_per_task))
    ray.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
