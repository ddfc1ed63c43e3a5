"""Shared input handling for the paper_figs scripts: every error goes to stderr with the file and
line and what was expected, and the script exits with status 2."""
import csv
import json
import math
import os
import sys


def fail(name, msg):
    print(f"{name}.py: error: {msg}", file=sys.stderr)
    sys.exit(2)


def read_table(name, path, columns, numeric=None, check=None, min_rows=1):
    """Rows of the CSV `path` as dicts. `columns` must all be in the header; those in `numeric`
    (default: all of them) are parsed as floats. `check(vals)` may return an error message for a
    row. Fails with the file and line of any bad value."""
    numeric = columns if numeric is None else numeric
    if not os.path.isfile(path):
        fail(name, f"{path} not found (run `softkin run experiments/{name}.json` first)")
    rows = []
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        header = reader.fieldnames or []
        missing = [c for c in columns if c not in header]
        if missing:
            fail(name, f"{path}: header lacks column(s) {', '.join(missing)}; "
                       f"expected {','.join(columns)}")
        for row in reader:
            line = reader.line_num
            if None in row or any(row.get(c) is None for c in columns):
                fail(name, f"{path}:{line}: expected {len(header)} values")
            vals = dict(row)
            for c in numeric:
                try:
                    vals[c] = float(row[c])
                except ValueError:
                    fail(name, f"{path}:{line}: column '{c}' is '{row[c]}', expected a number")
            why = check(vals) if check else None
            if why:
                fail(name, f"{path}:{line}: {why}")
            rows.append(vals)
    if len(rows) < min_rows:
        fail(name, f"{path}: needs at least {min_rows} data row(s), found {len(rows)}")
    return rows


def read_summary(name, path):
    """summary.json as a dict, {} if absent; fails if it is not a JSON object."""
    if not os.path.isfile(path):
        return {}
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        fail(name, f"{path}: not valid JSON ({e})")
    if not isinstance(data, dict):
        fail(name, f"{path}: expected a JSON object")
    return data


def save_figure(fig, results, name, dpi=130):
    """Lays out `fig`, writes it to RESULTS/<name>.png and says so; returns the path."""
    fig.tight_layout()
    out = os.path.join(results, f"{name}.png")
    fig.savefig(out, dpi=dpi)
    print(f"wrote {out}")
    return out


def results_dir(name, argv, doc):
    """The RESULTS_DIR argument of a plot script: prints `doc` for -h/--help (exit 0) or a wrong
    argument count (exit 2); fails if the folder does not exist."""
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(doc.strip(), file=sys.stderr)
        sys.exit(0 if len(argv) == 2 else 2)
    if not os.path.isdir(argv[1]):
        fail(name, f"results folder {argv[1]} does not exist")
    return argv[1]


MARKER_COLUMNS = ["variant", "step", "value", "marker", "x", "y", "z", "iterations", "time_s",
                  "converged"]
MARKER_NUMERIC = ["step", "value", "x", "y", "z", "iterations", "time_s", "converged"]


def read_marker_table(name, path):
    """Reads the markers.csv of a marker_sweep experiment (one row per variant x step x marker):
    steps must be non-negative integers, converged 0 or 1, and (variant, step, marker) unique."""
    seen = set()

    def check(v):
        if v["step"] < 0 or v["step"] != int(v["step"]):
            return f"step is {v['step']:g}, expected a non-negative integer"
        if v["converged"] not in (0.0, 1.0):
            return f"converged is {v['converged']:g}, expected 0 or 1"
        key = (v["variant"], int(v["step"]), v["marker"])
        if key in seen:
            return f"second row for variant {key[0]}, step {key[1]}, marker {key[2]}"
        seen.add(key)
        return None

    return read_table(name, path, MARKER_COLUMNS, MARKER_NUMERIC, check=check, min_rows=2)


WAYPOINT_COLUMNS = ["index", "target_x", "target_y", "target_z", "reached_x", "reached_y",
                    "reached_z", "error_mm", "objective", "converged", "termination", "iterations",
                    "evaluations", "fk_solves", "time_s", "jump", "inverted_elements"]
WAYPOINT_NUMERIC = [c for c in WAYPOINT_COLUMNS if c != "termination"]


def read_waypoints(name, path):
    """Reads a waypoint CSV of `softkin ik` or an IK experiment (ik/trajectory_io.hpp): one row
    per waypoint, indices consecutive, converged 0 or 1, error_mm >= 0 or -1 (not evaluated)."""
    state = {"next": None}

    def check(v):
        if state["next"] is not None and v["index"] != state["next"]:
            return f"index is {v['index']:g}, expected {state['next']:g}"
        state["next"] = v["index"] + 1
        if v["converged"] not in (0.0, 1.0):
            return f"converged is {v['converged']:g}, expected 0 or 1"
        if v["error_mm"] < 0 and v["error_mm"] != -1:
            return f"error_mm is {v['error_mm']:g}, expected >= 0 or -1"
        return None

    return read_table(name, path, WAYPOINT_COLUMNS, WAYPOINT_NUMERIC, check=check, min_rows=1)


def read_samples(name, path):
    """The configuration-space samples (c0.., x, y, z) an IK experiment wrote."""
    return read_table(name, path, ["x", "y", "z"], min_rows=1)


def read_ik_paths(name, results):
    """The summary, its non-empty 'paths' list and the configuration-space samples of an IK
    trajectory experiment (fig4_2, fig4_3, fig4_5)."""
    path = os.path.join(results, "summary.json")
    if not os.path.isfile(path):
        fail(name, f"{path}: missing (run the experiment first)")
    summary = read_summary(name, path)
    paths = summary.get("paths")
    if not isinstance(paths, list) or not paths:
        fail(name, f"{results}/summary.json: expected a non-empty 'paths' list")
    samples = read_samples(name, os.path.join(results, "samples.csv"))
    return summary, paths, samples


def read_path_waypoints(name, results, path):
    """The waypoint rows of one path entry of an IK experiment's summary (path_<name>.csv)."""
    return read_waypoints(name, os.path.join(results, f"path_{path.get('name', '?')}.csv"))


def plot_cylinder_sections(ax, config):
    """Draws the x-z cross-section of every cylinder obstacle of an experiment config (axis along
    y) on ax, labelled 'obstacle'."""
    for o in config.get("obstacles", []):
        if o.get("type") == "cylinder":
            b, r = o["base"], o["radius"]
            t = [2 * math.pi * k / 100 for k in range(101)]
            ax.plot([b[0] + r * math.cos(a) for a in t], [b[2] + r * math.sin(a) for a in t], "k-",
                    lw=1.5, label="obstacle")
