#!/usr/bin/env bash
# A stand-in Ray driver that keeps one batch: give it as `--python` of
#   tactrace search|sim-fit|tune ... --executor ray --ray-address 127.0.0.1:1 --python scripts/keep_batch.sh
# It answers "ready" (1 node, 1 CPU), writes the first batch the command
# sends (one JSON line: the evaluation's name, context, working folder and
# configurations) to $BATCH (default batch.jsonl in the command's working
# folder), then answers that the batch failed, so the command ends (exit 1)
# having evaluated nothing. No Ray is needed. examples/worker_threads.rs
# times a batch kept so.
echo '{"ready": {"nodes": 1, "cpus": 1}}'
head -n 1 > "${BATCH:-batch.jsonl}"
echo '{"error": {"kind": "evaluation", "message": "batch kept, not evaluated", "bad_input": false}}'
