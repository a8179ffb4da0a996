"""What ``bench accuracy`` prints and draws: the table, the skipping audit, the verdicts against the
targets, and run time against error with its Pareto front."""

from __future__ import annotations

from pathlib import Path

from autohaptics.bench.common import table
from autohaptics.bench.configs import NOSKIP, SKIP_STAGES, TARGETS

def pareto_front(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats on both axes (lower is better), sorted by x."""
    idx = []
    for i, (x, y) in enumerate(points):
        if not any((x2 <= x and y2 <= y) and (x2 < x or y2 < y) for j, (x2, y2) in enumerate(points) if j != i):
            idx.append(i)
    return sorted(idx, key=lambda i: points[i])


def print_tables(res: dict, log=print) -> None:
    d = res["decode"]
    log(f"\nbare decode: {d['wall_s']:.2f} s wall, {d.get('process_wall_s', 0.0):.2f} s whole process "
        f"({d['video_frames']} frames, {d['audio_samples']} samples), "
        f"peak RSS {d['peak_rss_mb']:.0f} MiB")
    rows = []
    for name, c in res["configs"].items():
        e = c.get("error") or {}
        rows.append([name, c["wall_s"], c["x_decode"], c.get("process_wall_s", ""), c.get("x_decode_process", ""),
                     c["x_decode_cpu"], c["analysis_stage_s"], c["peak_rss_mb"],
                     e.get("vibration_mae", ""), e.get("chair_mae", ""), e.get("onset_f1", ""),
                     e.get("onset_precision", ""), e.get("onset_recall", ""), e.get("chair_onset_f1", ""),
                     e.get("temperature_mae_c", ""), e.get("fan_iou", ""), e.get("fan_iou_tolerant", ""),
                     e.get("fan_ticks_f1", ""),
                     e.get("fan_iou_both_on", "")])
    log(table(rows, ["config", "wall_s", "x_decode", "process_s", "x_proc", "x_decode_cpu", "analysis_s", "peak_MiB",
                     "vib_MAE", "chair_MAE", "onset_F1", "onset_P", "onset_R", "chair_F1", "temp_MAE_C", "fan_IoU",
                     "fan_IoU_1cell", "fan_ticks_F1", "fan_IoU_both"]))
    log("(x_decode: wall / bare decode wall; process_s, x_proc: the same for the whole processes, start to exit; "
        "x_decode_cpu: the same in CPU seconds; analysis_s: audio pass + "
        "video stages except decode, from the stats; chair_*: the strongest actuator per tick; fan_ticks_F1: "
        "agreement on which ticks blow; fan_IoU_1cell: fan IoU with a one-cell tolerance (8-neighbourhood); "
        "fan_IoU_both: cell IoU where both blow)")
    log("\nwhere the time goes (seconds per stage, from the timelines' stats):")
    names = list(res["configs"])
    keys = list(dict.fromkeys(k for n in names for k in res["configs"][n]["stages"]))
    log(table([[k] + [res["configs"][n]["stages"].get(k, 0.0) for n in names] for k in keys], ["stage"] + names))
    audited = [n for n in ("balanced", NOSKIP) if n in res["configs"]]
    if audited:
        log("\nskipping audit (ticks computed / skipped per stage):")
        rows = []
        for stage in SKIP_STAGES:
            row = [stage]
            for n in audited:
                s = res["configs"][n]["skipping"].get(stage)
                row += [f"{s['computed']}/{s['skipped']}" if s else "-", s["share_computed"] if s else "",
                        s["seconds"] if s else ""]
            rows.append(row)
        header = ["stage"]
        for n in audited:
            header += [f"{n} done/skipped", "share_done", "s"]
        log(table(rows, header))
        for n in audited:
            sk = res["configs"][n]["skipping"]
            log(f"  {n}: {sk.get('static_ticks', 0)} static ticks (no flow), {sk.get('cuts', 0)} cuts")
        if "skip_cost" in res:
            b, ns = res["configs"]["balanced"], res["configs"][NOSKIP]
            cost = res["skip_cost"]["balanced_vs_noskip"]
            log(f"  skipping saves {ns['wall_s'] - b['wall_s']:.2f} s ({ns['wall_s']:.2f} -> {b['wall_s']:.2f} s); "
                f"balanced vs no-skip: vibration MAE {cost['vibration_mae']:.4f}, onset F1 {cost['onset_f1']:.3f}, "
                f"temperature MAE {cost['temperature_mae_c']:.3f} C, fan IoU {cost['fan_iou']:.3f} "
                f"(1 cell: {cost['fan_iou_tolerant']:.3f})")
            if "error" in b:
                be, ne = b["error"], ns["error"]
                log(f"  against the reference: balanced vibration MAE {be['vibration_mae']:.4f} / "
                    f"fan IoU {be['fan_iou']:.3f} (1 cell: {be['fan_iou_tolerant']:.3f}); "
                    f"no-skip {ne['vibration_mae']:.4f} / {ne['fan_iou']:.3f} (1 cell: {ne['fan_iou_tolerant']:.3f})")


def verdicts(res: dict) -> list[str]:
    """Target lines for the balanced and fast presets (met / NOT met), when both and the reference ran."""
    c = res["configs"]
    if not all(k in c for k in ("reference", "balanced")):
        return []
    b, e = c["balanced"], c["balanced"]["error"]
    checks = [("balanced wall / decode", b["x_decode"], "<=", TARGETS["x_decode"]),
              ("balanced wall / decode, whole processes", b.get("x_decode_process", float("nan")), "<=",
               TARGETS["x_decode"]),
              ("balanced vibration MAE", e["vibration_mae"], "<=", TARGETS["vibration_mae"]),
              ("balanced onset F1", e["onset_f1"], ">=", TARGETS["onset_f1"]),
              ("balanced temperature MAE (C)", e["temperature_mae_c"], "<=", TARGETS["temperature_mae_c"]),
              ("balanced fan IoU, one-cell tolerance", e["fan_iou_tolerant"], ">=", TARGETS["fan_iou_tolerant"])]
    if "fast" in c and c["fast"]["wall_s"] > 0:
        checks.append(("fast speed-up vs balanced (wall time)", b["wall_s"] / c["fast"]["wall_s"], ">=",
                       TARGETS["fast_speedup"]))
    if "fast" in c and c["fast"]["analysis_stage_s"] > 0:
        checks.append(("fast analysis speed-up vs balanced (stage seconds)",
                       b["analysis_stage_s"] / c["fast"]["analysis_stage_s"], ">=", TARGETS["fast_speedup"]))
    if "fast" in c and c["fast"]["analysis_s"] > 0:
        checks.append(("fast analysis speed-up vs balanced (wall - decode)", b["analysis_s"] / c["fast"]["analysis_s"],
                       ">=", TARGETS["fast_speedup"]))
    out = []
    for label, value, op, target in checks:
        ok = value <= target if op == "<=" else value >= target
        out.append(f"{label}: {value:.4g} (target {op} {target:g}): {'met' if ok else 'NOT met'}")
    return out


def plot(res: dict, path: Path) -> Path:
    """Run time against error, one point per configuration, Pareto front drawn (matplotlib Agg)."""
    import matplotlib
    import numpy as np

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import ticker

    names = [n for n, c in res["configs"].items() if "error" in c]
    x = [res["configs"][n]["x_decode"] for n in names]
    panels = [("vibration MAE", [res["configs"][n]["error"]["vibration_mae"] for n in names], TARGETS["vibration_mae"]),
              ("temperature MAE (C)", [res["configs"][n]["error"]["temperature_mae_c"] for n in names],
               TARGETS["temperature_mae_c"]),
              ("1 - fan IoU (one-cell tolerance)", [1.0 - res["configs"][n]["error"]["fan_iou_tolerant"] for n in names],
               1 - TARGETS["fan_iou_tolerant"])]
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), constrained_layout=True)
    for ax, (label, y, target) in zip(axes, panels):
        front = pareto_front(list(zip(x, y)))
        ax.plot([x[i] for i in front], [y[i] for i in front], "-", color="tab:orange", lw=2, zorder=1,
                label="Pareto front")
        span = (max(y) - min(y)) or 1.0
        placed: list[tuple[float, float]] = []
        for i, n in enumerate(names):
            on = i in front
            ax.scatter(x[i], y[i], s=60 if on else 40, zorder=2, color="tab:orange" if on else "tab:blue",
                       edgecolor="black" if on else "none")
            # labels of (nearly) coinciding points are stacked instead of printed over each other
            near = sum(1 for px, py in placed if abs(np.log10(px / x[i])) < 0.3 and abs(py - y[i]) < 0.1 * span)
            placed.append((x[i], y[i]))
            ax.annotate(n, (x[i], y[i]), textcoords="offset points", xytext=(5, 5 + 10 * near), fontsize=8)
        ax.axhline(target, color="grey", ls=":", lw=1, label="target")
        ax.axvline(TARGETS["x_decode"], color="grey", ls="--", lw=1, label=f"{TARGETS['x_decode']} x decode")
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _pos: f"{v:g}"))
        ax.xaxis.set_minor_formatter(ticker.NullFormatter())
        ax.set_xlabel("wall time / bare decode time")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=8, loc="best")
    v = res.get("video") or {}
    fig.suptitle(f"{Path(res['clip']).name}: {res['duration_s']:.1f} s"
                 + (f", {v['width']}x{v['height']} @ {v['fps']:.3g} fps" if v else "")
                 + f"; bare decode {res['decode']['wall_s']:.2f} s; errors against 'reference'", fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


