#!/usr/bin/python3
"""One Markdown table from several `seif consistency` outputs, a column per world.

Usage: consistency_table.py WORLD=OUT/nees.json [WORLD=OUT/nees.json ...]

Each cell: pose / landmark NEES (after the last step), then the mean squared landmark error
as a multiple of the batch MAP's over the paired runs, ± the half-width of its 95 % interval,
unaligned / aligned (when the world's run has the batch).
A filter missing from a world's run is left blank; failed runs are counted in the cell.
"""
import json
import sys


def fmt(x):
    if x is None:
        return "–"
    if abs(x) >= 1000:
        return f"{x:,.0f}".replace(",", " ")
    if abs(x) >= 100:
        return f"{x:.0f}"
    if abs(x) >= 10:
        return f"{x:.1f}"
    return f"{x:.2f}"


def ratio(f, key):
    """The MSE ratio to the batch over the paired runs, ± its 95 % half-width."""
    r = f[key]
    if r is None or r["ratio"] is None:
        return "–"
    if f["name"] == "batch" or r["ci95"] is None or r["pairs"] < 2:
        return fmt(r["ratio"])
    return f"{fmt(r['ratio'])} ± {fmt(r['ci95'])}"


def row_name(f):
    return f["name"] + (" [posterior mean]" if f.get("estimate") == "posterior" else "")


def cells(path):
    data = json.load(open(path))
    filters = data["filters"]
    batch = next((f for f in filters if f["name"] == "batch" and f.get("estimate") != "posterior"), None)
    out = {}
    for f in filters:
        text = f"{fmt(f['pose_nees_final'])} / {fmt(f['landmark_nees_final'])}"
        if batch is not None:
            text += f", {ratio(f, 'mse_ratio_to_batch')} / {ratio(f, 'mse_aligned_ratio_to_batch')}"
        else:
            text += f", aligned {f['error_aligned_final']:.3f} m"
        if f.get("failed_runs"):
            text += f" ({len(f['failed_runs'])} runs failed)"
        out[row_name(f)] = text
    return out, data


def main(argv):
    if len(argv) < 2 or any("=" not in a for a in argv[1:]):
        sys.exit(__doc__)
    worlds = [a.split("=", 1) for a in argv[1:]]
    tables = [(w, *cells(p)) for w, p in worlds]
    order = []
    for _, c, _ in tables:
        order += [n for n in c if n not in order]
    heads = [f"{w} ({d['runs']})" for w, _, d in tables]
    print("| filter | " + " | ".join(heads) + " |")
    print("|---|" + "---|" * len(heads))
    for n in order:
        print(f"| {n} | " + " | ".join(c.get(n, "") for _, c, _ in tables) + " |")


if __name__ == "__main__":
    main(sys.argv)
