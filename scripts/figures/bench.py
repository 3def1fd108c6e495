#!/usr/bin/python3
"""Figure of `seif bench`: time per step and memory against the map size N, log-log.

Usage: /usr/bin/python3 scripts/figures/bench.py DIR/bench.json [OUT.png]

Reads bench.json (written by `seif bench`) and writes OUT.png (default: bench.png next to
bench.json) with two panels:

  left   median time per filter step against N, one line per filter, the band between the
         median and the 90th percentile shaded (with `--association`, the median association
         time per scan dashed); cases the benchmark skipped (they would not
         fit the memory or time budget) are marked with an x at the top of the axis
  right  the filter's own peak memory per mapped landmark against N (bounded for the SEIF,
         growing like N for the dense filters)

Exits with status 3 (and one line on stderr) when matplotlib is not installed; `seif bench`
then prints how to render the figure later.
"""
import json
import sys
from pathlib import Path

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("bench.py: matplotlib is not installed", file=sys.stderr)
    sys.exit(3)

STYLE = {
    "ekf": dict(color="tab:red", marker="o", label="EKF (dense covariance)"),
    "eif": dict(color="tab:orange", marker="s", label="EIF (dense information)"),
    "seif": dict(color="tab:blue", marker="^", label="SEIF (constant time)"),
}


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 1
    source = Path(argv[1])
    out = Path(argv[2]) if len(argv) > 2 else source.with_name("bench.png")
    doc = json.loads(source.read_text())
    results = doc["results"]
    filters = []
    for r in results:
        if r["filter"] not in filters:
            filters.append(r["filter"])

    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(11, 4.4))
    all_n = [r["landmarks"] for r in results]
    skipped_any = False
    for i, f in enumerate(filters):
        style = dict(STYLE.get(f, dict(marker="o", label=f)))
        label = style.pop("label")
        done = sorted((r for r in results if r["filter"] == f and "skipped" not in r),
                      key=lambda r: r["landmarks"])
        skipped = [r for r in results if r["filter"] == f and "skipped" in r]
        if done:
            n = [r["landmarks"] for r in done]
            med = [r["us_per_step_median"] for r in done]
            p90 = [r["us_per_step_p90"] for r in done]
            ax_t.plot(n, med, label=label, **style)
            ax_t.fill_between(n, med, p90, color=style.get("color"), alpha=0.15, linewidth=0)
            assoc = [r for r in done if r.get("scans", 0) > 0]
            if assoc:  # `seif bench --association`: the association per scan, dashed
                ax_t.plot([r["landmarks"] for r in assoc], [r["us_association_per_scan_median"] for r in assoc],
                          linestyle="--", label=f"{label}: association per scan ({assoc[0]['association']})",
                          **style)
            per = [(r["landmarks"], 1024 * 1024 * r["mb_per_landmark"]) for r in done
                   if r.get("mb_per_landmark", 0) > 0]
            if per:
                ax_m.plot([p[0] for p in per], [p[1] for p in per], label=label, **style)
        if skipped:
            skipped_any = True
            # one row of x per filter, just below the top of the axis
            ax_t.plot([r["landmarks"] for r in skipped], [0.96 - 0.05 * i] * len(skipped),
                      linestyle="none", marker="x", markersize=8, color=style.get("color"),
                      transform=ax_t.get_xaxis_transform())

    for ax in (ax_t, ax_m):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("landmarks in the map N")
        ax.grid(True, which="both", alpha=0.3)
        if all_n:
            ax.set_xlim(min(all_n) / 1.5, max(all_n) * 1.5)
    ax_t.set_ylabel("time per step [µs] (median; shaded to p90)")
    title = "time per filter step"
    if skipped_any:
        title += "  (x: skipped, over the budget)"
    ax_t.set_title(title, fontsize=10)
    ax_t.legend(fontsize=8, loc="center right")
    ax_m.set_ylabel("filter peak memory per landmark [bytes]")
    ax_m.set_title("memory per landmark", fontsize=10)
    ax_m.legend(fontsize=8, loc="upper left")

    machine = doc.get("machine", {})
    cfg = doc.get("config", {})
    fig.suptitle(f"seif bench: corridor world, last {cfg.get('window', '?')} steps timed; "
                 f"{machine.get('cpu_model', '?')}, {machine.get('cores', '?')} cores", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
