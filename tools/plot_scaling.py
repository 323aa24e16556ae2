"""Table and plot of bench/femreg_scaling_bench's JSON: ms per frame against mesh size, one
line per cloud size (the default preconditioner), a dashed one for the sparse factor at every
size, and the per-phase split. Usage: plot_scaling.py scaling.json OUT_DIR"""
import csv
import json
import sys
from pathlib import Path

import matplotlib

# bench/femreg_scaling_bench's third argument.
PRECONDITIONERS = {0: "auto", 1: "factor", 2: "multigrid"}

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def DataWeight(b):
    """The fourth argument: per area, or per pair with its N/m when not the default 200."""
    if b.get("per_area", 0):
        return "per area"
    n = b.get("data_per_pair", 200.0)
    return "per pair" if n == 200.0 else f"per pair, {n:g} N/m"


def main():
    data = json.loads(Path(sys.argv[1]).read_text())
    out = Path(sys.argv[2])
    rows = []
    for b in data["benchmarks"]:
        if b.get("run_type") == "aggregate" or "error_occurred" in b:
            continue
        frames = b["items_per_second"] * b["real_time"] / 1e3
        ms = b["real_time"] / frames  # real_time is for the iteration's frames (ms)
        rows.append({
            "vertices": int(b["vertices"]), "tets": int(b["tets"]), "points": int(b["points"]),
            "points_used": int(round(b["points_used"])),
            # Before 2026-11-27 there was no choice: the default was the factor at every size.
            "preconditioner": PRECONDITIONERS[int(b.get("preconditioner", 0))],
            # The fourth argument (from 2026-11-27 on): the data weight per pair or per area.
            "data_weight": DataWeight(b),
            # The fifth argument (from 2026-12-01 on): solver.threads; one before.
            "threads": int(b.get("threads", 1)), "ms_per_frame": ms,
            # The first frame (pattern, analysis, hierarchy, first touch of their memory) and the
            # mean of the later ones (from 2026-12-02 on; NaN before).
            "first_frame_ms": b.get("first_frame_ms", float("nan")),
            "later_frame_ms": b.get("later_frame_ms", float("nan")),
            "correspondences_ms": b["correspondences_ms"], "rotations_ms": b["rotations_ms"],
            "solve_ms": b["solve_ms"], "preprocess_ms": b["preprocess_ms"],
            # The solve's parts and counts (benchmarks from 2026-11-26 on; 0 before).
            "assembly_ms": b.get("assembly_ms", 0.0), "factorization_ms": b.get("factorization_ms", 0.0),
            "linear_solve_ms": b.get("linear_solve_ms", 0.0),
            "factorizations": b.get("factorizations", 0.0), "pcg_iterations": b.get("pcg_iterations", 0.0),
            "outer_iterations": b.get("outer_iterations", 0.0),
            "converged": b["converged"],
            # Mean vertex error against the shape the clouds were sampled from (from
            # 2026-11-28 on).
            "error_mm": b.get("error_mm", float("nan")),
        })
    rows.sort(key=lambda r: (r["threads"], r["data_weight"] != "per pair", r["data_weight"],
                             r["preconditioner"] != "auto", r["points"], r["vertices"]))
    with open(out / "scaling.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.2f}" if isinstance(v, float) else v) for k, v in r.items()})
    lines = ["| vertices | tets | cloud points (used) | preconditioner | data weight | threads | ms/frame | "
             "first frame / later frames (ms) | correspondences | "
             "rotations | solve "
             "(assembly / factorization or hierarchy / linear solves) | factorizations or hierarchies, PCG iterations, outer iterations "
             "per frame | preprocess | converged | error (mm) |",
             "|---:|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['vertices']} | {r['tets']} | {r['points']} ({r['points_used']}) | {r['preconditioner']} | "
                     f"{r['data_weight']} | {r['threads']} | "
                     f"{r['ms_per_frame']:.1f} | {r['first_frame_ms']:.0f} / {r['later_frame_ms']:.1f} | "
                     f"{r['correspondences_ms']:.1f} | {r['rotations_ms']:.1f} | {r['solve_ms']:.1f} "
                     f"({r['assembly_ms']:.0f} / {r['factorization_ms']:.0f} / {r['linear_solve_ms']:.0f}) | "
                     f"{r['factorizations']:.1f}, {r['pcg_iterations']:.0f}, {r['outer_iterations']:.1f} | "
                     f"{r['preprocess_ms']:.1f} | {100 * r['converged']:.0f}% | {r['error_mm']:.3f} |")
    (out / "table.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    fig, ax = plt.subplots(figsize=(6, 4.2))
    rows = [r for r in rows if r["threads"] == 1]  # the plot: one thread, the mesh's cost
    default = [r for r in rows if r["preconditioner"] == "auto" and r["data_weight"] == "per pair"]
    for points in sorted({r["points"] for r in default}):
        sel = [r for r in default if r["points"] == points]
        ax.loglog([r["vertices"] for r in sel], [r["ms_per_frame"] for r in sel], "o-", label=f"{points} points")
    # What a long sequence pays per frame: the frames after the first (its setup apart).
    later = sorted([r for r in default if r["points"] == min(r["points"] for r in default)
                    and r["later_frame_ms"] == r["later_frame_ms"]], key=lambda r: r["vertices"])
    if later:
        ax.loglog([r["vertices"] for r in later], [r["later_frame_ms"] for r in later], "o:", color="C0",
                  label=f"{later[0]['points']} points, frames after the first")
    # The factor at every size: the auto rows below the switch and the factor rows above it.
    factor = [r for r in rows if r["preconditioner"] == "factor"]
    if factor:
        points = factor[0]["points"]
        sizes = {r["vertices"] for r in factor}
        sel = sorted([r for r in factor if r["points"] == points] +
                     [r for r in default if r["points"] == points and r["vertices"] < min(sizes)],
                     key=lambda r: r["vertices"])
        ax.loglog([r["vertices"] for r in sel], [r["ms_per_frame"] for r in sel], "s--", color="0.5",
                  label=f"{points} points, sparse factor throughout")
    others = sorted({r["data_weight"] for r in rows} - {"per pair"})
    for i, weight in enumerate(others):
        sel = [r for r in rows if r["data_weight"] == weight]
        points = sel[0]["points"]
        sel = sorted([r for r in sel if r["points"] == points], key=lambda r: r["vertices"])
        ax.loglog([r["vertices"] for r in sel], [r["ms_per_frame"] for r in sel], "^-." if i == 0 else "v-.",
                  color=f"C{4 + i}", label=f"{points} points, data weight {weight}")
    v = sorted({r["vertices"] for r in rows})
    if v:
        base = min(r["ms_per_frame"] for r in rows if r["vertices"] == v[0])
        ax.loglog(v, [base * x / v[0] for x in v], "k:", label="linear growth")
    ax.set_xlabel("mesh vertices")
    ax.set_ylabel("ms per frame (1 thread)")
    ax.set_title("femreg fast back end: cost against size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "scaling.png", dpi=120)


if __name__ == "__main__":
    main()
