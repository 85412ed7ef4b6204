"""Figures and the page of `handeye report` (matplotlib and PyYAML, Debian's python3-matplotlib, python3-yaml).

Reads DIR/report.yaml (io::format_report) and DIR/calibration.yaml (the result file) and writes
  DIR/residuals.png      each sample's residual in sigmas, the rejected ones marked, the advice threshold
  DIR/ellipsoids.png     X's 1-sigma ellipsoids: translation (mm) and rotation (deg)
  DIR/checks.png         1 sigma per axis: predicted, leave-one-out, split-half
  DIR/noise.png          the noise the covariance rests on (estimated values with their 1 sigma, or as given)
  DIR/rotation_axes.png  the motions' rotation axes in the camera frame, and how much each direction was turned
  DIR/report.html        the page: X, the advice, the figures and the tables
Usage: python3 scripts/report.py DIR
"""
import html
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

AXES = ["x", "y", "z", "rx", "ry", "rz"]
REJECTED, KEPT, WARN = "#c0392b", "#2e86c1", "#e67e22"


def covariance_of(calibration):
    return np.array(calibration["covariance"]["pose"], dtype=float).reshape(6, 6)


def rpy_deg(q):
    x, y, z, w = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return [math.degrees(a) for a in (roll, pitch, yaw)]


def residuals_figure(report, path):
    samples = report["samples"]
    index = [s["index"] for s in samples]
    sigma = [max(s["sigma"], 1e-3) for s in samples]
    colors = [REJECTED if s["rejected"] else (WARN if s["sigma"] > report["advice_sigma"] else KEPT) for s in samples]
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    ax = axes[0]
    ax.bar(index, sigma, color=colors)
    ax.axhline(report["advice_sigma"], color="k", ls="--", lw=1, label=f"advice threshold {report['advice_sigma']:.2f} sigma")
    ax.legend(fontsize=8, loc="upper right")
    median = float(np.median(sigma))
    if max(sigma) > 20 * median:
        ax.set_yscale("log")
    for s in samples:
        if s["rejected"] or s["sigma"] > report["advice_sigma"]:
            ax.annotate(f"#{s['index']}: {s['sigma']:.1f}", (s["index"], max(s["sigma"], 1e-3)), ha="center",
                        va="bottom", fontsize=8, color=REJECTED if s["rejected"] else WARN)
    ax.set_ylabel("residual [sigma, 6 dof]")
    ax.set_title("Each sample against X (red: rejected, orange: beyond the advice threshold, blue: kept)")
    ax.grid(True, axis="y", alpha=0.3)
    ax = axes[1]
    ax.plot(index, [s["residual_mm"] for s in samples], "o-", color=KEPT, label="translation [mm]")
    ax2 = ax.twinx()
    ax2.plot(index, [s["residual_deg"] for s in samples], "s--", color="#7d3c98", label="rotation [deg]")
    for s in samples:
        if s["rejected"]:
            ax.axvspan(s["index"] - 0.4, s["index"] + 0.4, color=REJECTED, alpha=0.15)
    ax.set_ylabel("translation [mm]", color=KEPT)
    ax2.set_ylabel("rotation [deg]", color="#7d3c98")
    if max(s["residual_mm"] for s in samples) > 20 * max(1e-9, float(np.median([s["residual_mm"] for s in samples]))):
        ax.set_yscale("log")
        ax2.set_yscale("log")
    ax.set_xlabel("sample (counted from 0, as /remove_sample and the panel)")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def ellipsoid_axes(ax, covariance, scale, unit, title, color):
    values, vectors = np.linalg.eigh(covariance * scale * scale)
    radii = np.sqrt(np.maximum(values, 0.0))
    u, v = np.mgrid[0:2 * np.pi:40j, 0:np.pi:20j]
    sphere = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)], axis=-1)
    points = sphere @ np.diag(radii) @ vectors.T
    ax.plot_surface(points[..., 0], points[..., 1], points[..., 2], color=color, alpha=0.35, linewidth=0)
    for k in range(3):
        axis = vectors[:, k] * radii[k]
        ax.plot([-axis[0], axis[0]], [-axis[1], axis[1]], [-axis[2], axis[2]], color="k", lw=1)
    r = max(radii.max(), 1e-12) * 1.1
    ax.set_xlim(-r, r)
    ax.set_ylim(-r, r)
    ax.set_zlim(-r, r)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"y [{unit}]")
    ax.set_zlabel(f"z [{unit}]")
    sigma = np.sqrt(np.maximum(np.diag(covariance), 0.0)) * scale
    ax.set_title(f"{title}\n1 sigma x, y, z: {sigma[0]:.3g}, {sigma[1]:.3g}, {sigma[2]:.3g} {unit}", fontsize=10)


def ellipsoids_figure(calibration, frames, path):
    covariance = covariance_of(calibration)
    fig = plt.figure(figsize=(11, 5))
    ellipsoid_axes(fig.add_subplot(1, 2, 1, projection="3d"), covariance[:3, :3], 1e3, "mm",
                   f"translation of X ({frames['parent']} <- {frames['camera']})", KEPT)
    ellipsoid_axes(fig.add_subplot(1, 2, 2, projection="3d"), covariance[3:, 3:], 180 / math.pi, "deg",
                   f"rotation of X (left perturbation, {frames['parent']} frame)", "#7d3c98")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def checks_figure(report, path):
    checks = report["checks"]
    series = [("predicted", checks["predicted_sigma"], "#34495e"),
              (f"leave-one-out ({checks['leave_one_out_solved']} solves)", checks["leave_one_out_sigma"], "#16a085")]
    if checks["split_half_splits"] > 0:
        series.append((f"split-half ({checks['split_half_splits']} splits, NEES {checks['split_half_nees_middle']:.2f}; "
                       f"honest here {checks['honest_nees']:.2f})",
                       checks["split_half_sigma"], "#d35400"))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    width = 0.8 / len(series)
    for ax, sl, unit in ((axes[0], slice(0, 3), "mm"), (axes[1], slice(3, 6), "deg")):
        for k, (name, values, color) in enumerate(series):
            x = np.arange(3) + (k - (len(series) - 1) / 2) * width
            ax.bar(x, values[sl], width, label=name, color=color)
        ax.set_xticks(np.arange(3))
        ax.set_xticklabels(AXES[sl])
        ax.set_ylabel(f"1 sigma of X [{unit}]")
        ax.grid(True, axis="y", alpha=0.3)
    axes[0].set_title("translation")
    axes[1].set_title("rotation")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="lower center", ncol=3, frameon=False)
    fig.suptitle("Is the covariance honest? Three views of X's 1 sigma per axis (alike when it is)")
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def noise_rows(calibration):
    """(name, value, sigma, unit label, supported) for the figure and the table."""
    noise = calibration.get("noise", {})
    rows = []
    for c in noise.get("estimated", []):
        scale, unit = {"m": (1e3, "mm"), "rad": (180 / math.pi, "deg")}.get(c["unit"], (1.0, "scale"))
        rows.append((c["name"], c["value"] * scale, c["sigma"] * scale, unit, c["supported"]))
    if rows:
        return rows, "estimated from the residuals"
    model = noise.get("model", {})
    for who in ("effector", "pattern", "A", "B"):
        block = model.get(who)
        if not block:
            continue
        if "pose" in block:
            diag = np.diag(np.array(block["pose"], dtype=float).reshape(6, 6))
        else:
            diag = np.concatenate([np.diag(np.array(block["translation"], dtype=float).reshape(3, 3)),
                                   np.diag(np.array(block["rotation"], dtype=float).reshape(3, 3))])
        for k in range(6):
            scale, unit = (1e3, "mm") if k < 3 else (180 / math.pi, "deg")
            rows.append((f"{who} {AXES[k]}", math.sqrt(max(diag[k], 0.0)) * scale, None, unit, None))
    return rows, "as given (the noise block, or the mean of the detections' own covariances)"


def noise_figure(calibration, path):
    rows, origin = noise_rows(calibration)
    fig, axes = plt.subplots(1, 2, figsize=(11, max(3.0, 0.32 * len(rows) + 1.2)))
    for ax, unit in ((axes[0], "mm"), (axes[1], "deg")):
        mine = [r for r in rows if r[3] == unit or (unit == "mm" and r[3] == "scale")]
        names = [f"{r[0]}{' (at its bound)' if r[4] is False else ''}" + (" [scale]" if r[3] == "scale" else "") for r in mine]
        y = np.arange(len(mine))
        ax.barh(y, [r[1] for r in mine], xerr=[r[2] or 0.0 for r in mine],
                color=["#aab7b8" if r[4] is False else KEPT for r in mine],
                capsize=3)
        ax.set_yticks(y)
        ax.set_yticklabels(names, fontsize=8)
        ax.invert_yaxis()
        ax.set_xlabel(f"1 sigma [{unit}]")
        ax.grid(True, axis="x", alpha=0.3)
    fig.suptitle(f"The noise the covariance rests on ({origin}; error bars: its own 1 sigma)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return rows, origin


def rotation_axes_figure(report, path):
    axes_list = np.array(report["rotation_axes"], dtype=float).reshape(-1, 4)
    turning = report["turning"]
    fig = plt.figure(figsize=(11, 5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    if len(axes_list):
        points = np.vstack([axes_list[:, :3], -axes_list[:, :3]])  # an axis has no sign
        angles = np.concatenate([axes_list[:, 3], axes_list[:, 3]])
        s = ax.scatter(points[:, 0], points[:, 1], points[:, 2], c=angles, cmap="viridis", s=10)
        fig.colorbar(s, ax=ax, shrink=0.6, pad=0.15, label="rotation angle [deg]")
    weakest = np.array(turning["axes"][0])
    ax.plot([-weakest[0], weakest[0]], [-weakest[1], weakest[1]], [-weakest[2], weakest[2]], color=REJECTED, lw=3,
            label="least turned-about direction")
    ax.set_xlim(-1, 1)
    ax.set_ylim(-1, 1)
    ax.set_zlim(-1, 1)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("camera x")
    ax.set_ylabel("camera y")
    ax.set_zlabel("camera z (optical)")
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title("rotation axes of the motions between samples\n(camera frame, both signs)", fontsize=10)
    ax = fig.add_subplot(1, 2, 2)
    values = np.array(turning["eigenvalues_rad2"], dtype=float)
    share = values / max(values.max(), 1e-300)
    labels = [f"({a[0]:+.2f}, {a[1]:+.2f}, {a[2]:+.2f})" for a in turning["axes"]]
    ax.bar(range(3), share, color=[REJECTED if v < 0.1 else KEPT for v in share])
    ax.axhline(0.1, color="k", ls="--", lw=1)
    ax.set_xticks(range(3))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel("turning about it / the most turned direction")
    ax.set_title("how much the motions turned about each principal direction\n(sum of angle^2 a a^T; dashed: advice below 0.1)",
                 fontsize=10)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(header, rows, row_class=None):
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>"]
    for i, row in enumerate(rows):
        cls = f' class="{row_class(i)}"' if row_class and row_class(i) else ""
        out.append(f"<tr{cls}>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>")
    return "\n".join(out) + "</table>"


def page(report, calibration, noise, path):
    checks = report["checks"]
    frames = report["frames"]
    t = [v * 1e3 for v in calibration["translation"]]
    rpy = rpy_deg(calibration["rotation"])
    sigma = checks["predicted_sigma"]
    obj = report["object"]
    reached = obj["reached"]  # target_progress's decision (next_best_pose.h), not sigma <= target alone
    samples = report["samples"]
    rejected = [s for s in samples if s["rejected"]]
    parts = [f"""<!DOCTYPE html><html><head><meta charset="utf-8"><title>Hand-eye calibration report</title>
<style>
body {{ font-family: sans-serif; margin: 24px; max-width: 1200px; color: #222; }}
h1 {{ font-size: 22px; }} h2 {{ font-size: 18px; margin-top: 28px; border-bottom: 1px solid #ccc; }}
table {{ border-collapse: collapse; font-size: 13px; margin: 8px 0; }}
td, th {{ border: 1px solid #ccc; padding: 3px 8px; text-align: right; }} th {{ background: #f2f2f2; }}
td:first-child, td:last-child {{ text-align: left; }}
tr.rejected td {{ background: #fadbd8; }} tr.off td {{ background: #fdebd0; }}
.advice li {{ margin: 4px 0; }} .advice {{ background: #fef9e7; border: 1px solid #f4d03f; padding: 8px 24px; }}
img {{ max-width: 100%; border: 1px solid #eee; }} .small {{ color: #666; font-size: 12px; }}
</style></head><body>
<h1>Hand-eye calibration report</h1>
<p class="small">{html.escape(str(report['source']))} &middot; {html.escape(str(report.get('setup', '')))} &middot;
method {html.escape(str(report['method']))} &middot; {len(samples)} samples, {len(rejected)} rejected</p>
<h2>X = T_{html.escape(frames['parent'])}_{html.escape(frames['camera'])}</h2>
""",
             table(["", "x", "y", "z", "roll", "pitch", "yaw"],
                   [["value [mm, deg]"] + [f"{v:+.2f}" for v in t] + [f"{v:+.3f}" for v in rpy],
                    ["1 sigma [mm, deg]"] + [f"{v:.3f}" for v in sigma[:3]] + [f"{v:.4f}" for v in sigma[3:]]]),
             f"""<p class="small">Rotation 1 sigma about the {html.escape(frames['parent'])} axes (rx, ry, rz; the roll-pitch-yaw
is for reading the value only). An object {obj['working_distance_m']:.2f} m in front of the camera is known to
<b>{obj['sigma_mm']:.2f} mm</b> (1 sigma, worst axis) from X alone; target {obj['target_mm']:.2f} mm:
<b>{'reached' if reached else 'not reached'}</b>.</p>
<h2>Advice</h2><ul class="advice">""",
             "".join(f"<li>{html.escape(a)}</li>" for a in report["advice"]),
             "</ul>",
             "<h2>Samples</h2><img src=\"residuals.png\" alt=\"per-sample residuals\">",
             table(["#", "residual [mm]", "residual [deg]", "sigma", "state"],
                   [[s["index"], f"{s['residual_mm']:.3f}", f"{s['residual_deg']:.4f}", f"{s['sigma']:.2f}",
                     "rejected: " + s.get("reason", "") if s["rejected"] else "kept"] for s in samples],
                   lambda i: "rejected" if samples[i]["rejected"] else ("off" if samples[i]["sigma"] > report["advice_sigma"] else "")),
             f"""<p class="small">sigma: the residual's Mahalanobis length (6 dof) under its predicted covariance; kept
samples of an honest session average about 2.4 (sqrt of 6). Advice threshold {report['advice_sigma']:.2f} sigma.</p>
<h2>X's uncertainty</h2><img src="ellipsoids.png" alt="covariance ellipsoids">
<h2>Leave-one-out and split-half checks</h2><img src="checks.png" alt="checks">""",
             table(["1 sigma", "x [mm]", "y [mm]", "z [mm]", "rx [deg]", "ry [deg]", "rz [deg]"],
                   [[name] + [f"{v:.3f}" for v in values[:3]] + [f"{v:.4f}" for v in values[3:]]
                    for name, values in (("predicted", checks["predicted_sigma"]),
                                         ("leave-one-out", checks["leave_one_out_sigma"]),
                                         ("split-half", checks["split_half_sigma"]))]),
             f"""<p class="small">Leave-one-out: the jackknife over {checks['leave_one_out_solved']} solves without one sample
each. Split-half: {checks['split_half_splits']} random halves of {checks['split_half_size']} samples; the mean NEES of
their difference is {checks['split_half_nees']:.2f} (translation {checks['split_half_nees_translation']:.2f},
rotation {checks['split_half_nees_rotation']:.2f}), {checks['split_half_nees_middle']:.2f} over the middle 90% of the
splits. An honest covariance on these same robot poses, with this session's fitted noise, gives
{checks['honest_nees']:.2f} (5-95%: {checks['honest_nees_band'][0]:.2f} to {checks['honest_nees_band'][1]:.2f}, from
{checks['honest_sessions']} simulated sessions checked the same way), not a fixed 6: small halves and a noise
estimated from them make it larger. Verdict: <b>{html.escape(checks['honesty_text'])}</b>.
{html.escape(checks.get('split_half_problem', ''))}</p>
<h2>Noise</h2><img src="noise.png" alt="noise">""",
             table(["component", "1 sigma", "its 1 sigma", "unit", "supported by the residuals"],
                   [[r[0], f"{r[1]:.4g}", "-" if r[2] is None else f"{r[2]:.2g}", r[3],
                     "given" if r[4] is None else ("yes" if r[4] else "no (at its bound)")] for r in noise[0]]),
             f"<p class=\"small\">{html.escape(noise[1])}. {html.escape(str(calibration.get('noise', {}).get('how', '')))}</p>",
             """<h2>Rotation axes</h2><img src="rotation_axes.png" alt="rotation axes">
<p class="small">X's rotation is pinned only about directions the motions turn about; a direction turned about
less than a tenth of the best one is called out in the advice.</p></body></html>"""]
    with open(path, "w") as f:
        f.write("\n".join(parts))


def main():
    out = sys.argv[1]
    report = yaml.safe_load(open(f"{out}/report.yaml"))
    calibration = yaml.safe_load(open(f"{out}/calibration.yaml"))
    residuals_figure(report, f"{out}/residuals.png")
    ellipsoids_figure(calibration, report["frames"], f"{out}/ellipsoids.png")
    checks_figure(report, f"{out}/checks.png")
    noise = noise_figure(calibration, f"{out}/noise.png")
    rotation_axes_figure(report, f"{out}/rotation_axes.png")
    page(report, calibration, noise, f"{out}/report.html")


if __name__ == "__main__":
    main()
