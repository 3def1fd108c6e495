#!/usr/bin/python3
"""Figure of one or more `seif run` outputs over the same dataset: trajectories, maps and,
when given, GPS fixes and dead reckoning, in the GPS frame (or the first run's frame).

Usage: /usr/bin/python3 scripts/figures/run_map.py OUT.png [--gps GPS] [--ellipses] [--title T] RUN_DIR[=LABEL]...

Each RUN_DIR holds trajectory.tum, map.csv and (optionally) dead_reckoning.tum from `seif
run`; `seif plot RUN_DIR` draws one with its gps.csv and ellipses into RUN_DIR/map.png.
When the first RUN_DIR holds the dataset's ground truth (groundtruth.tum,
landmarks_groundtruth.csv: simulated worlds, MRCLAM), it is drawn, and without --gps each
trajectory and map are aligned to it as to the GPS fixes (the legend's RMSE is at the ground
truth's stamps, so it can differ a little from metrics.json's ate_rmse, taken at the run's).
When RUN_DIR also holds associations.csv (a run with --association nn or jcbb), each
observation the data's ids score wrong is drawn as a thin line from the pose it was made
at to the landmark that holds it at the end, duplicate landmarks (the label of an older
one) as squares and landmarks none of whose observations has an id as grey circles.
--ellipses draws each landmark's 95 % covariance ellipse (map.csv's cov_xx, cov_xy, cov_yy).
With --gps (time x y per line, '#' comments, or a CSV "time,x,y" such as `seif run`'s
gps.csv), each trajectory and its map are moved by
the rigid 2-D motion that best aligns the trajectory, interpolated at the GPS stamps, to the
fixes (least squares, as metrics.json's gps_rmse); the first run's dead reckoning is drawn
aligned the same way (its own best fit). Without --gps, everything is drawn as estimated.
Each input is checked before drawing (fields per row, finite numbers, at least one pose and
times that never go backwards, map.csv's header, unique integer ids and positive
semi-definite covariances, associations.csv's header, times inside the trajectory, verdicts
that agree with truth and label, landmarks in map.csv; an optional file that is a dangling
or looping link is an error, not left out); the first problem is printed as one line
`run_map.py: FILE:LINE: what is wrong (found 'TEXT')`, bytes that are not printable as \\xNN,
and the script exits with status 2.
Exits with status 3 when matplotlib is not installed.
"""
import math
import os
import sys
from pathlib import Path

import numpy as np

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Ellipse
except ImportError:
    print("run_map.py: matplotlib is not installed", file=sys.stderr)
    sys.exit(3)

COLORS = ["tab:red", "tab:blue", "tab:green", "tab:purple"]


class InputError(Exception):
    """A corrupt input; its text is `FILE:LINE: what is wrong (found 'TEXT')`."""


def printable(text):
    """`text` with each byte that did not decode and each character that is not printable as \\xNN."""
    out = []
    for ch in str(text):
        code = ord(ch)
        if 0xDC80 <= code <= 0xDCFF:  # an undecodable byte (read_lines' surrogateescape)
            out.append(f"\\x{code - 0xDC00:02x}")
        elif not ch.isprintable():
            out.append(f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}")
        else:
            out.append(ch)
    return "".join(out)


def fail(path, line, what, found):
    raise InputError(f"{path}:{line}: {what} (found '{printable(found)}')")


def read_lines(path, comments=False):
    """The non-blank lines of `path` as (line number, stripped text); '#' lines left out if `comments`."""
    try:
        text = Path(path).read_text(errors="surrogateescape")
    except OSError as e:
        fail(path, 0, "cannot be read", e.strerror)
    lines = [(n, l.strip()) for n, l in enumerate(text.split("\n"), 1) if l.strip()]
    return [(n, l) for n, l in lines if not (comments and l.startswith("#"))]


def read_rows(path, lines, count, sep=None):
    """The rows of `lines` as an array of `count` finite numbers each (fields split at `sep`)."""
    rows = []
    for n, line in lines:
        fields = line.split(sep)
        if len(fields) != count:
            fail(path, n, f"expected {count} fields, got {len(fields)}", line)
        values = []
        for f in fields:
            try:
                values.append(float(f))
            except ValueError:
                fail(path, n, "not a number", f.strip())
            if not math.isfinite(values[-1]):
                fail(path, n, "not a finite number", f.strip())
        rows.append(values)
    return np.array(rows).reshape(-1, count)


def check_header(path, lines, headers):
    """The first line of `lines`, which must be one of `headers`."""
    n, line = lines[0] if lines else (1, "")
    if line not in headers:
        fail(path, n, "expected the header " + " or ".join(f"'{h}'" for h in headers), line)
    return line


def check_not_empty(path, rows, what):
    """`rows` has at least one row (else the file has no `what`)."""
    if len(rows) == 0:
        fail(path, 1, f"no {what} in the file", "")


def check_time_order(path, lines, times):
    """Times that never go backwards (the poses are interpolated in time)."""
    for k in range(1, len(times)):
        if times[k] < times[k - 1]:
            fail(path, lines[k][0], f"time going backwards (after {times[k - 1]:.6f})", lines[k][1])


def read_tum(path):
    """(time, x, y) of each pose of a TUM file (`t x y z qx qy qz qw`, '#' comments); at least
    one, in time order."""
    lines = read_lines(path, comments=True)
    rows = read_rows(path, lines, 8)
    check_not_empty(path, rows, "pose")
    check_time_order(path, lines, rows[:, 0])
    return rows[:, :3]


def read_gps(path):
    """GPS fixes (time, x, y): a CSV with the header "time,x,y", or a whitespace table ('#' comments)."""
    lines = read_lines(path, comments=True)
    if lines and "," in lines[0][1]:
        check_header(path, lines, ["time,x,y"])
        rows = read_rows(path, lines[1:], 3, ",")
    else:
        rows = read_rows(path, lines, 3)
    check_not_empty(path, rows, "GPS fix")
    return rows


def check_ids(path, lines, values):
    """Landmark ids (the first field of each of `lines`), each an integer, none repeated."""
    seen = set()
    for (n, line), i in zip(lines, values):
        if i != int(i):
            fail(path, n, "landmark id not an integer", line.split(",")[0])
        if int(i) in seen:
            fail(path, n, "landmark id repeated", line.split(",")[0])
        seen.add(int(i))
    return values.astype(int)


MAP_HEADERS = ["id,x,y", "id,x,y,cov_xx,cov_xy,cov_yy"]  # as src/io/results.cpp writes map.csv


def read_map(path):
    """Landmark ids (N), positions (N x 2) and 2x2 covariances (N x 2 x 2, or None without)."""
    lines = read_lines(path)
    header = check_header(path, lines, MAP_HEADERS)
    rows = read_rows(path, lines[1:], header.count(",") + 1, ",")
    ids = check_ids(path, lines[1:], rows[:, 0])
    if header == MAP_HEADERS[0]:
        return ids, rows[:, 1:3], None
    for (n, line), (vxx, vxy, vyy) in zip(lines[1:], rows[:, 3:6]):
        # positive semi-definite, up to the 9 significant digits map.csv is written with
        if min(vxx, vyy) < 0:
            fail(path, n, f"negative variance {'cov_xx' if vxx < 0 else 'cov_yy'}", line)
        if abs(vxy) > math.sqrt(vxx * vyy) * (1 + 1e-6):
            fail(path, n, "covariance not positive semi-definite: |cov_xy| > sqrt(cov_xx cov_yy)", line)
    return ids, rows[:, 1:3], rows[:, [3, 4, 4, 5]].reshape(-1, 2, 2)


# as src/eval/run_associations.cpp writes associations.csv
ASSOCIATIONS_HEADER = "step,time,index,z0,z1,truth,outcome,landmark,d2,provisional,applied,final_landmark,label,verdict"
VERDICTS = ("", "correct", "wrong", "duplicate")


def read_associations(path, map_ids, span):
    """From associations.csv: the wrong ones (time, landmark at the end), the duplicate
    landmarks, the landmarks with a label, the scored count and the correct count. Each time
    lies in `span`, the trajectory's (first, last) stamp."""
    lines = read_lines(path)
    check_header(path, lines, [ASSOCIATIONS_HEADER])
    columns = ASSOCIATIONS_HEADER.split(",")
    at = {c: k for k, c in enumerate(columns)}
    known = set(int(i) for i in map_ids)
    wrong, duplicates, labelled, scored, correct = [], set(), set(), 0, 0
    for n, line in lines[1:]:
        fields = line.split(",")
        if len(fields) != len(columns):
            fail(path, n, f"expected {len(columns)} fields, got {len(fields)}", line)
        verdict = fields[at["verdict"]]
        if verdict not in VERDICTS:
            fail(path, n, "verdict not one of correct, wrong, duplicate or empty", verdict)
        try:
            time = float(fields[at["time"]])
        except ValueError:
            fail(path, n, "time not a number", fields[at["time"]])
        if not math.isfinite(time):
            fail(path, n, "time not a finite number", fields[at["time"]])
        if not span[0] <= time <= span[1]:
            fail(path, n, f"time outside the trajectory's [{span[0]:.6f}, {span[1]:.6f}]", fields[at["time"]])
        label = fields[at["label"]]
        if label and not label.lstrip("-").isdigit():
            fail(path, n, "label not an integer", label)
        final = fields[at["final_landmark"]]
        if not final:
            if verdict:
                fail(path, n, "a verdict for an observation in no landmark", line)
            continue
        try:
            landmark = int(final)
        except ValueError:
            fail(path, n, "final_landmark not an integer", final)
        if landmark not in known:
            fail(path, n, "final_landmark is not in map.csv", final)
        if label:
            labelled.add(landmark)
        if not verdict:
            continue
        # A scored observation has a truth id, so its landmark has a label; correct means equal.
        if not label:
            fail(path, n, f"verdict '{verdict}' for a landmark without a label", line)
        if (verdict == "wrong") == (label == fields[at["truth"]]):
            fail(path, n, f"verdict '{verdict}' where truth {'equals' if verdict == 'wrong' else 'differs from'} label", line)
        scored += 1
        correct += verdict == "correct"
        if verdict == "duplicate":
            duplicates.add(landmark)
        if verdict != "correct":
            wrong.append((time, landmark))
    return wrong, duplicates, labelled, scored, correct


def read_truth(d):
    """The ground truth a run folder holds: poses (time, x, y) or None, landmarks (N x 2) or None."""
    poses, landmarks = None, None
    if present(d / "groundtruth.tum"):
        poses = read_tum(d / "groundtruth.tum")
    if present(d / "landmarks_groundtruth.csv"):
        path = d / "landmarks_groundtruth.csv"
        lines = read_lines(path)
        check_header(path, lines, ["id,x,y"])
        rows = read_rows(path, lines[1:], 3, ",")
        check_ids(path, lines[1:], rows[:, 0])
        landmarks = rows[:, 1:3]
    return poses, landmarks


def present(path):
    """Whether `path` is there at all: a dangling or looping link is, and reading it then fails."""
    return os.path.lexists(path)


def read_run(d, dead_reckoning):
    """A run folder's trajectory, map (ids, positions, covariances), (if asked and present)
    dead reckoning, and (if present) its associations (read_associations)."""
    traj, (ids, lm, lm_cov) = read_tum(d / "trajectory.tum"), read_map(d / "map.csv")
    dr_file, assoc_file = d / "dead_reckoning.tum", d / "associations.csv"
    dr = read_tum(dr_file) if dead_reckoning and present(dr_file) else None
    assoc = read_associations(assoc_file, ids, (traj[0, 0], traj[-1, 0])) if present(assoc_file) else None
    return traj, ids, lm, lm_cov, dr, assoc


def draw_associations(ax, traj, ids, m, xy_of, assoc, color):
    """associations.csv over the map `m` (drawn positions of `ids`): each wrong observation
    as a line from the pose at its time (`xy_of`) to its landmark; duplicates and landmarks
    without a label marked."""
    wrong, duplicates, labelled, scored, correct = assoc
    where = {int(i): k for k, i in enumerate(ids)}
    if wrong:
        t = np.array([w[0] for w in wrong])
        poses = xy_of(np.column_stack([np.interp(t, traj[:, 0], traj[:, 1]), np.interp(t, traj[:, 0], traj[:, 2])]))
        ends = m[[where[w[1]] for w in wrong]]
        segments = np.stack([poses, ends], axis=1)
        ax.add_collection(LineCollection(segments, colors=color, linewidths=0.4, alpha=0.35, zorder=2))
    share = f", {100.0 * correct / scored:.2f} % of {scored} right" if scored else ""
    ax.plot([], [], "-", color=color, lw=0.4, alpha=0.6, label=f"wrong associations ({len(wrong)}{share})")
    dup = m[[where[i] for i in sorted(duplicates)]].reshape(-1, 2)
    ax.plot(dup[:, 0], dup[:, 1], "s", mfc="none", mec=color, ms=6, mew=0.8, zorder=5,
            label=f"duplicate landmarks ({len(dup)})")
    unlabelled = [k for k, i in enumerate(ids) if int(i) not in labelled]
    if unlabelled:
        u = m[unlabelled]
        ax.plot(u[:, 0], u[:, 1], "o", mfc="none", mec="0.45", ms=5, mew=0.7, zorder=5,
                label=f"landmarks without a labelled observation ({len(u)})")


CHI2_95_2DOF = 5.991  # the 95 % quantile of chi-square with 2 degrees of freedom


def draw_ellipses(ax, xy, cov, color):
    """The 95 % ellipse of each landmark (x - m)^T P^-1 (x - m) = 5.991."""
    for m, P in zip(xy, cov):
        w, v = np.linalg.eigh(P)
        w = np.maximum(w, 0.0)
        angle = np.degrees(np.arctan2(v[1, 1], v[0, 1]))
        ax.add_patch(Ellipse(m, 2 * np.sqrt(CHI2_95_2DOF * w[1]), 2 * np.sqrt(CHI2_95_2DOF * w[0]),
                             angle=angle, fill=False, ec=color, lw=0.5, alpha=0.7, zorder=4))


def rigid_fit(p, q):
    """R, t minimising sum |R p_i + t - q_i|^2 (2-D, no scale)."""
    cp, cq = p.mean(axis=0), q.mean(axis=0)
    a, b = p - cp, q - cq
    sxx = (a * b).sum()
    sxy = (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum()
    ang = np.arctan2(sxy, sxx)
    R = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
    return R, cq - R @ cp


def aligned(traj, gps):
    """The trajectory's (R, t) to the frame of `gps` (time, x, y: GPS fixes or ground-truth
    positions), and the RMSE at their stamps; (I, 0, None) when fewer than two lie inside it."""
    inside = (gps[:, 0] >= traj[0, 0]) & (gps[:, 0] <= traj[-1, 0])
    if inside.sum() < 2:
        return np.eye(2), np.zeros(2), None
    g = gps[inside]
    p = np.column_stack([np.interp(g[:, 0], traj[:, 0], traj[:, 1]), np.interp(g[:, 0], traj[:, 0], traj[:, 2])])
    R, t = rigid_fit(p, g[:, 1:3])
    rmse = np.sqrt((((p @ R.T + t) - g[:, 1:3]) ** 2).sum(axis=1).mean())
    return R, t, rmse


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 1
    out = argv[1]
    gps_file, title, runs, ellipses = None, "", [], False
    i = 2
    while i < len(argv):
        if argv[i] == "--gps":
            gps_file = argv[i + 1]
            i += 2
        elif argv[i] == "--ellipses":
            ellipses = True
            i += 1
        elif argv[i] == "--title":
            title = argv[i + 1]
            i += 2
        else:
            d, _, label = argv[i].partition("=")
            runs.append((Path(d), label or Path(d).name))
            i += 1
    try:  # every input is read and checked before anything is drawn
        gps = read_gps(gps_file) if gps_file else None
        inputs = [read_run(d, k == 0) for k, (d, _) in enumerate(runs)]
        truth, truth_landmarks = read_truth(runs[0][0]) if runs else (None, None)
    except InputError as e:
        print(f"run_map.py: {e}", file=sys.stderr)
        return 2
    fig, ax = plt.subplots(figsize=(9, 8))
    if gps is not None:
        ax.plot(gps[:, 1], gps[:, 2], ".", color="0.6", ms=2.5, label=f"GPS fixes ({len(gps)})", zorder=1)
    if truth is not None:
        ax.plot(truth[:, 1], truth[:, 2], "-", color="0.55", lw=1.6, alpha=0.7, label="ground truth", zorder=1)
    if truth_landmarks is not None:
        ax.plot(truth_landmarks[:, 0], truth_landmarks[:, 1], "o", color="0.2", ms=3.5,
                label=f"true landmarks ({len(truth_landmarks)})", zorder=3)
    reference, reference_name = (gps, "GPS") if gps is not None else (truth, "ATE")
    for k, ((_, label), (traj, ids, lm, lm_cov, dr, assoc)) in enumerate(zip(runs, inputs)):
        R, t, note = np.eye(2), np.zeros(2), ""
        if reference is not None:
            R, t, rmse = aligned(traj, reference)
            note = f", {reference_name} RMSE {rmse:.2f} m" if rmse is not None else ""
        xy = traj[:, 1:3] @ R.T + t
        c = COLORS[k % len(COLORS)]
        ax.plot(xy[:, 0], xy[:, 1], "-", color=c, lw=0.9, label=f"{label} trajectory{note}", zorder=3)
        m = lm @ R.T + t
        ax.plot(m[:, 0], m[:, 1], "+", color=c, ms=5, mew=1.0, label=f"{label} map ({len(lm)} landmarks)", zorder=4)
        if ellipses and lm_cov is not None:
            draw_ellipses(ax, m, R @ lm_cov @ R.T, c)
            ax.plot([], [], "-", color=c, lw=0.5, label=f"{label} 95 % ellipses")
        if assoc is not None:
            draw_associations(ax, traj, ids, m, lambda p, R=R, t=t: p @ R.T + t, assoc, c)
        if dr is not None:
            Rd, td, note = np.eye(2), np.zeros(2), ""
            if reference is not None:
                Rd, td, rmse = aligned(dr, reference)
                note = f", {reference_name} RMSE {rmse:.1f} m" if rmse is not None else ""
            dxy = dr[:, 1:3] @ Rd.T + td
            ax.plot(dxy[:, 0], dxy[:, 1], ":", color="0.3", lw=0.8, label=f"dead reckoning{note}", zorder=2)
    ax.set_aspect("equal", adjustable="datalim")
    frame = " (GPS frame)" if gps is not None else " (ground-truth frame)" if truth is not None else ""
    ax.set_xlabel("x [m]" + frame)
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
