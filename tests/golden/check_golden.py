#!/usr/bin/env python3
"""Golden runs: `--quick` experiment summaries checked against reference metrics with margins.

Usage: check_golden.py SOFTKIN_BIN SOURCE_DIR [--update]

For each entry of tests/golden/manifest.json, runs `softkin run CONFIG --quick --no-plot` into a
temporary folder and compares every listed metric of its summary.json (a path of keys and list
indices, e.g. "paths/0/tips/-1/0") with the reference value: |value - reference| must be within
abs + rel * |reference|. Prints every drift with the config, the metric, both values and the
margin, and exits 1 if any metric drifted (2 if a run failed or a metric is missing).

--update rewrites the manifest's reference values from this run (after a change that is meant to
move them; say why in the commit).
"""
import json
import os
import subprocess
import sys
import tempfile


def lookup(summary, path):
    at = summary
    for part in path.split("/"):
        if isinstance(at, list):
            at = at[int(part)]
        elif isinstance(at, dict) and part in at:
            at = at[part]
        else:
            raise KeyError(part)
    if isinstance(at, bool) or not isinstance(at, (int, float)):
        raise KeyError(f"{path} is not a number")
    return float(at)


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    softkin, source = argv[1], argv[2]
    update = "--update" in argv[3:]
    manifest_path = os.path.join(source, "tests", "golden", "manifest.json")
    with open(manifest_path) as f:
        manifest = json.load(f)
    drifts, failures, checked = [], [], 0
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "2"))
    with tempfile.TemporaryDirectory(prefix="softkin_golden_") as tmp:
        for entry in manifest["runs"]:
            config = os.path.join(source, entry["config"])
            run = subprocess.run([softkin, "run", config, "--quick", "--no-plot", "--results", tmp],
                                 capture_output=True, text=True, env=env)
            name = os.path.splitext(os.path.basename(config))[0]
            if run.returncode != 0:
                failures.append(f"{entry['config']}: exit {run.returncode}\n{run.stderr[-2000:]}")
                continue
            with open(os.path.join(tmp, name, "summary.json")) as f:
                summary = json.load(f)
            for metric in entry["metrics"]:
                try:
                    value = lookup(summary, metric["path"])
                except (KeyError, IndexError, ValueError) as e:
                    failures.append(f"{entry['config']}: metric {metric['path']}: missing ({e})")
                    continue
                checked += 1
                if update:
                    metric["value"] = value
                    continue
                ref = metric["value"]
                margin = metric.get("abs", 0.0) + metric.get("rel", 0.0) * abs(ref)
                if not abs(value - ref) <= margin:
                    drifts.append(f"{entry['config']}: {metric['path']} = {value!r}, reference "
                                  f"{ref!r}, margin {margin:g} ({metric.get('why', '')})")
    for line in failures + drifts:
        print("golden: " + line, file=sys.stderr)
    if update and not failures:
        with open(manifest_path, "w") as f:
            json.dump(manifest, f, indent=2)
            f.write("\n")
        print(f"golden: updated {checked} reference value(s) in {manifest_path}")
        return 0
    print(f"golden: {checked} metric(s) of {len(manifest['runs'])} run(s) checked, "
          f"{len(drifts)} drifted, {len(failures)} failure(s)")
    return 2 if failures else (1 if drifts else 0)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
