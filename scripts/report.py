#!/usr/bin/env python3
"""Error against run time: turn `softhap_bench accuracy` JSON lines into a report.

    python3 scripts/report.py report/accuracy.jsonl report/ [--cost cpu|wall]

writes report/accuracy.md (tables) and PNG plots beside it:
  dynamic_<mesh>.png    log-log error vs run time, one panel per material, one curve per method
  oscillator.png        1-DOF oscillator: error vs dt (measured orders) and error vs run time

The run time ("cost") is the CPU time of each run's step loop by default: the library runs on one
thread, so it equals the run's wall time on an idle core, and unlike the wall time it is not
inflated by other processes sharing the machine. --cost wall uses the wall-clock time instead.
  static_eb.png         linear tets against Euler-Bernoulli as the mesh is refined
  static_nonlinear.png  nonlinear materials against linear elasticity as the tip load grows

Needs numpy and matplotlib (`make report` installs matplotlib when it is missing).
"""
import json
import math
import os
import sys

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

METHODS = ["forward_euler", "symplectic_euler", "rk2", "rk4", "implicit_euler_n1", "implicit_euler_newton"]
LABELS = {
    "forward_euler": "forward Euler",
    "symplectic_euler": "symplectic Euler",
    "rk2": "RK2 (midpoint)",
    "rk4": "RK4",
    "implicit_euler_n1": "implicit Euler, 1 Newton it.",
    "implicit_euler_newton": "implicit Euler, Newton 1e-8",
}
STYLE = {
    "forward_euler": ("tab:red", "v"),
    "symplectic_euler": ("tab:blue", "o"),
    "rk2": ("tab:orange", "s"),
    "rk4": ("tab:green", "D"),
    "implicit_euler_n1": ("tab:purple", "^"),
    "implicit_euler_newton": ("tab:brown", "P"),
}
MATERIALS = ["linear", "stvk", "corotational", "neohookean"]
THRESHOLDS = (1e-2, 1e-3)

# Cost of a run: "cpu" (CPU time of the step loop; the library is single-threaded, so this is the
# wall time on an idle core) or "wall" (wall-clock time, inflated when other processes compete).
COST = "cpu"
COST_LABEL = {"cpu": "CPU time", "wall": "wall time"}


def cost(row):
    value = row.get("cpu_s") if COST == "cpu" else None
    return value if value is not None else row["wall_s"]


def load(path):
    rows = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line:
                continue
            try:
                rows.append(json.loads(line))
            except json.JSONDecodeError as e:
                sys.exit(f"report.py: {path}:{number}: not JSON ({e})")
    return rows


def study(rows, name):
    return [r for r in rows if r.get("study") == name]


def fmt_time(seconds):
    if seconds is None or not math.isfinite(seconds):
        return "-"
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.3g} ms"
    return f"{seconds * 1e6:.3g} µs"


def fmt_err(error):
    if error is None or not math.isfinite(error):
        return "-"
    percent = 100.0 * error
    if percent >= 0.01:
        return f"{percent:.3g} %"
    return f"{error:.2g}"


def fmt_dt(dt):
    return fmt_time(dt)


def slope(dts, errors, lo=1e-10, hi=0.1):
    """Least-squares slope of log(error) against log(dt) over the points in [lo, hi]."""
    pairs = [(d, e) for d, e in zip(dts, errors) if e is not None and lo <= e <= hi]
    if len(pairs) < 2:
        return None
    x = np.log([p[0] for p in pairs])
    y = np.log([p[1] for p in pairs])
    return float(np.polyfit(x, y, 1)[0])


def richardson(h, w):
    """Order p and limit w0 of w(h) = w0 + C h^p through three points (h ascending), or None."""
    d1, d2 = w[1] - w[0], w[2] - w[1]
    if d1 == 0 or d2 / d1 <= 0:
        return None

    def f(p):
        return (h[2] ** p - h[1] ** p) / (h[1] ** p - h[0] ** p) - d2 / d1

    lo, hi = 0.05, 8.0
    if f(lo) * f(hi) > 0:
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(lo) * f(mid) <= 0:
            hi = mid
        else:
            lo = mid
    p = 0.5 * (lo + hi)
    c = d1 / (h[1] ** p - h[0] ** p)
    return p, w[0] - c * h[0] ** p


def mesh_key(row):
    return (row["ny"], row["mesh"])


# ------------------------------------------------------------------------------------------------
# Dynamic


def dynamic_tables(rows, refs, out):
    runs = study(rows, "dynamic")
    meshes = sorted({mesh_key(r) for r in runs})
    summary = {}
    lines = []
    c = "CPU" if COST == "cpu" else "wall"
    lines.append(f"| mesh | material | method | cheapest to 1 %: dt (dt/dt_crit), {c}, error "
                 f"| cheapest to 0.1 %: dt (dt/dt_crit), {c}, error | best error ({c}) | order | unstable |")
    lines.append("|---|---|---|---|---|---|---|---|")
    for ny, mesh in meshes:
        for material in MATERIALS:
            for method in METHODS:
                sel = [r for r in runs if r["ny"] == ny and r["material"] == material and r["method"] == method]
                if not sel:
                    continue
                ok = [r for r in sel if r["status"] == "ok" and r["error"] is not None]
                cells = []
                for threshold in THRESHOLDS:
                    good = [r for r in ok if r["error"] <= threshold]
                    if good:
                        best = min(good, key=cost)
                        ratio = best.get("dt_over_critical")
                        ratio_text = f" ({ratio:.2f})" if ratio is not None else ""
                        cells.append(f"{fmt_dt(best['dt'])}{ratio_text}, {fmt_time(cost(best))}, {fmt_err(best['error'])}")
                        summary[(ny, material, method, threshold)] = best
                    else:
                        cells.append("not reached")
                        summary[(ny, material, method, threshold)] = None
                if ok:
                    best_error = min(ok, key=lambda r: r["error"])
                    best_text = f"{fmt_err(best_error['error'])} ({fmt_time(cost(best_error))})"
                else:
                    best_text = "-"
                finest = sorted((r for r in ok if r["error"] >= 1e-11), key=lambda r: r["dt"])[:3]
                order = slope([r["dt"] for r in finest], [r["error"] for r in finest], lo=1e-11, hi=1.0)
                order_text = f"{order:.2f}" if order is not None else "-"
                bad = [r for r in sel if r["status"] != "ok"]
                if bad:
                    ratios = sorted({f"{r['dt_over_critical']:.2f}" for r in bad if r.get("dt_over_critical")}, reverse=True)
                    bad_text = f"{len(bad)}/{len(sel)} ({r_status(bad)} at dt/dt_crit {', '.join(ratios)})"
                else:
                    bad_text = f"0/{len(sel)}"
                lines.append(f"| {mesh} | {material} | {LABELS[method]} | {cells[0]} | {cells[1]} | {best_text} "
                             f"| {order_text} | {bad_text} |")
    out.extend(lines)
    return summary, meshes


def r_status(bad):
    return "/".join(sorted({r["status"] for r in bad}))


def summary_table(summary, ny, mesh, out):
    out.append(f"| method ({mesh}) | " + " | ".join(MATERIALS) + " |")
    out.append("|---|" + "---|" * len(MATERIALS))
    for method in METHODS:
        cells = []
        for material in MATERIALS:
            parts = []
            for threshold in THRESHOLDS:
                best = summary.get((ny, material, method, threshold))
                parts.append(fmt_time(cost(best)) if best else "not reached")
            cells.append(" / ".join(parts))
        out.append(f"| {LABELS[method]} | " + " | ".join(cells) + " |")


def reference_table(rows, out):
    refs = study(rows, "dynamic_reference")
    runs = study(rows, "dynamic")
    out.append(f"| mesh | material | reference | steps | {COST_LABEL[COST]} | max displacement at 0.5 s | tip z | "
               "reference error estimate |")
    out.append("|---|---|---|---|---|---|---|---|")
    for ref in sorted(refs, key=lambda r: (r["ny"], MATERIALS.index(r["material"]))):
        rk4 = [r for r in runs if r["ny"] == ref["ny"] and r["material"] == ref["material"] and r["method"] == "rk4"
               and r["status"] == "ok" and r["error"]]
        estimate = "-"
        if rk4:
            finest = min(rk4, key=lambda r: r["dt"])
            value = finest["error"] * (ref["dt"] / finest["dt"]) ** 4
            estimate = f"{value:.1e}" if value >= 1e-15 else f"{value:.0e} (below round-off, ~1e-13)"
        out.append(f"| {ref['mesh']} | {ref['material']} | RK4, dt = {fmt_dt(ref['dt'])} | {ref['steps']} "
                   f"| {fmt_time(cost(ref))} | {1e3 * ref['max_displacement']:.2f} mm "
                   f"| {1e3 * ref['tip_z']:.2f} mm | {estimate} |")


def method_handles():
    """Legend entries for every method (also those with no stable run) and the unstable marker."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=STYLE[m][0], marker=STYLE[m][1], label=LABELS[m]) for m in METHODS]
    handles.append(Line2D([], [], color="black", marker="x", linestyle="none", markersize=8,
                          label="rolled back as unstable (at its run time)"))
    return handles


def dynamic_plots(rows, meshes, outdir):
    runs = study(rows, "dynamic")
    names = []
    for ny, mesh in meshes:
        sel_mesh = [r for r in runs if r["ny"] == ny]
        walls = [max(cost(r), 1e-6) for r in sel_mesh]
        xmin = 10 ** math.floor(math.log10(min(walls)))
        xmax = 10 ** math.ceil(math.log10(max(walls)))
        fig, axes = plt.subplots(2, 2, figsize=(12, 9.5), sharex=True, sharey=True)
        for ax, material in zip(axes.flat, MATERIALS):
            for method in METHODS:
                sel = sorted((r for r in sel_mesh if r["material"] == material and r["method"] == method),
                             key=lambda r: r["dt"], reverse=True)
                ok = [r for r in sel if r["status"] == "ok" and r["error"]]
                color, marker = STYLE[method]
                if ok:
                    ax.loglog([cost(r) for r in ok], [r["error"] for r in ok], marker=marker, color=color,
                              markersize=6, linewidth=1.5)
                bad = [r for r in sel if r["status"] != "ok"]
                if bad:  # unstable runs: at the top edge, at their (short) wall time
                    ax.scatter([max(cost(r), xmin) for r in bad], [3.0] * len(bad), marker="x", color=color,
                               s=50, linewidths=2)
            for threshold, style in zip(THRESHOLDS, ("--", ":")):
                ax.axhline(threshold, color="grey", linestyle=style, linewidth=1)
                ax.text(xmin * 1.3, threshold * 1.2, f"{100 * threshold:g} %", color="grey", fontsize=9)
            ax.set_title(material)
            ax.grid(True, which="major", alpha=0.3)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_ylim(1e-13, 10)
            ax.set_xlim(xmin, xmax)
        for ax in axes[1]:
            ax.set_xlabel(f"{COST_LABEL[COST]} of the run to t = 0.5 s (s)")
        for ax in axes[:, 0]:
            ax.set_ylabel("error at t = 0.5 s")
        fig.legend(handles=method_handles(), loc="lower center", ncol=4, fontsize=10, frameon=False)
        tets = sel_mesh[0]["tets"]
        fig.suptitle(f"Cantilever under gravity, mesh {mesh} ({tets} tets): error against run time\n"
                     "error = max node |x - x_ref| / reference tip displacement; reference RK4 at 1/16 of the "
                     "smallest explicit dt", fontsize=12)
        fig.tight_layout(rect=(0, 0.06, 1, 0.95))
        name = f"dynamic_{mesh}.png"
        fig.savefig(os.path.join(outdir, name), dpi=110)
        plt.close(fig)
        names.append(name)
    return names


def implicit_extrapolation(runs, ny, material, method, target=1e-2):
    """Steps, dt and cost an implicit sweep that stopped short of target would need, from the order
    and cost per step of its two smallest steps; None if it reached target or cannot tell."""
    ok = sorted((r for r in runs if r["ny"] == ny and r["material"] == material and r["method"] == method
                 and r["status"] == "ok" and r["error"]), key=lambda r: r["dt"])
    if len(ok) < 2 or ok[0]["error"] <= target:
        return None
    a, b = ok[0], ok[1]
    p = math.log(b["error"] / a["error"]) / math.log(b["dt"] / a["dt"])
    if not 0.3 < p < 3.0:
        return None
    factor = (a["error"] / target) ** (1.0 / p)
    return {"order": p, "steps": a["steps"] * factor, "dt": a["dt"] / factor, "cost": cost(a) * factor}


def observations(rows, summary, meshes, out):
    runs = study(rows, "dynamic")
    for ny, mesh in meshes:
        out.append(f"- **{mesh}**:")
        for material in MATERIALS:
            best1 = [(m, summary.get((ny, material, m, 1e-2))) for m in METHODS]
            best1 = [(m, r) for m, r in best1 if r]
            if not best1:
                continue
            method, row = min(best1, key=lambda t: cost(t[1]))
            text = (f"{material}: cheapest to 1 % is {LABELS[method]} at dt/dt_crit = "
                    f"{row['dt_over_critical']:.2f} ({fmt_time(cost(row))}, error {fmt_err(row['error'])})")
            ex = implicit_extrapolation(runs, ny, material, "implicit_euler_n1")
            se = next((r for r in runs if r["ny"] == ny and r["material"] == material
                       and r["method"] == "symplectic_euler"), None)
            if ex and se:
                text += (f"; implicit Euler (1 Newton it.) would need dt ~ {fmt_dt(ex['dt'])} "
                         f"({ex['dt'] / se['dt_critical']:.2f} x the explicit dt_crit) and ~{fmt_time(ex['cost'])}, "
                         f"{ex['cost'] / cost(row):.0f} x more (extrapolated with its observed order "
                         f"{ex['order']:.2f})")
            out.append(f"  - {text}.")
        # One Newton iteration against Newton to 1e-8 at equal dt.
        pairs = []
        for material in MATERIALS:
            n1 = {r["steps"]: r for r in runs if r["ny"] == ny and r["material"] == material
                  and r["method"] == "implicit_euler_n1" and r["status"] == "ok"}
            nt = {r["steps"]: r for r in runs if r["ny"] == ny and r["material"] == material
                  and r["method"] == "implicit_euler_newton" and r["status"] == "ok"}
            for steps in sorted(set(n1) & set(nt)):
                pairs.append((material, steps, n1[steps], nt[steps]))
        nonlinear = [t for t in pairs if t[0] != "linear"]
        if nonlinear:
            worst = max(nonlinear, key=lambda t: abs(t[2]["error"] - t[3]["error"]) / t[3]["error"])
            small = [t for t in nonlinear if t[1] >= 80]
            spread = max((abs(t[2]["error"] - t[3]["error"]) / t[3]["error"] for t in small), default=float("nan"))
            ratio = np.median([cost(t[3]) / cost(t[2]) for t in nonlinear])
            iterations = np.mean([t[3]["newton_mean"] for t in nonlinear])
            out.append(f"  - implicit Euler, Newton to 1e-8 against one iteration (nonlinear materials, same dt): "
                       f"{iterations:.1f} Newton iterations per step on average, {ratio:.1f} x the cost, and the "
                       f"same error within {100 * spread:.1f} % (relative) once dt <= 0.5 s / 80; the largest "
                       f"difference is at dt = {fmt_dt(worst[2]['dt'])} ({worst[0]}: "
                       f"{fmt_err(worst[2]['error'])} with one iteration, {fmt_err(worst[3]['error'])} with Newton).")
        fe = [r for r in runs if r["ny"] == ny and r["method"] == "forward_euler"]
        if fe:
            stable = [r["dt"] for r in fe if r["status"] == "ok"]
            unstable = [r["dt"] for r in fe if r["status"] != "ok"]
            if stable and unstable:
                out.append(f"  - forward Euler: stable up to dt = {fmt_dt(max(stable))}, rolled back from "
                           f"dt = {fmt_dt(min(unstable))} (explicit dt_crit {fmt_dt(fe[0]['dt_critical'])}; "
                           "with stiffness damping beta it needs dt < beta).")


# ------------------------------------------------------------------------------------------------
# Oscillator


def oscillator(rows, out, outdir):
    runs = study(rows, "oscillator")
    if not runs:
        return None
    orders = {}
    out.append("| method | measured order | error at dt = 1/64 s | error at dt = 1/1024 s | smallest error (dt) | "
               f"{COST_LABEL[COST]} of the 1/1024 s run |")
    out.append("|---|---|---|---|---|---|")
    for method in METHODS:
        sel = sorted((r for r in runs if r["method"] == method and r["status"] == "ok" and r["error"] is not None),
                     key=lambda r: r["dt"])
        if not sel:
            continue
        order = slope([r["dt"] for r in sel], [r["error"] for r in sel], lo=1e-11, hi=0.05)
        orders[method] = order
        at = {r["steps"]: r for r in sel}
        smallest = min(sel, key=lambda r: r["error"])
        out.append(f"| {LABELS[method]} | {order:.2f} | {fmt_err(at[64]['error']) if 64 in at else '-'} "
                   f"| {fmt_err(at[1024]['error']) if 1024 in at else '-'} "
                   f"| {smallest['error']:.1e} ({fmt_dt(smallest['dt'])}) "
                   f"| {fmt_time(cost(at[1024])) if 1024 in at else '-'} |")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    for method in METHODS:
        sel = sorted((r for r in runs if r["method"] == method and r["status"] == "ok" and r["error"]),
                     key=lambda r: r["dt"])
        if not sel:
            continue
        color, marker = STYLE[method]
        label = LABELS[method] + (f" (order {orders[method]:.2f})" if orders.get(method) else "")
        ax1.loglog([r["dt"] for r in sel], [r["error"] for r in sel], marker=marker, color=color, label=label)
        ax2.loglog([cost(r) for r in sel], [r["error"] for r in sel], marker=marker, color=color,
                   label=LABELS[method])
    ax1.set_xlabel("dt (s)")
    ax1.set_ylabel("phase-space error at t = 1 s / amplitude")
    ax1.set_title("1-DOF oscillator (omega = 5 rad/s): error against dt")
    ax1.legend(fontsize=8)
    ax2.set_xlabel(f"{COST_LABEL[COST]} of the run (s)")
    ax2.set_title(f"error against {COST_LABEL[COST]} (per-call overhead dominates)")
    for ax in (ax1, ax2):
        ax.grid(True, which="major", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "oscillator.png"), dpi=110)
    plt.close(fig)
    return "oscillator.png"


# ------------------------------------------------------------------------------------------------
# Static


def static_eb(rows, out, outdir):
    runs = study(rows, "static_eb")
    if not runs:
        return None
    poissons = sorted({r["poisson"] for r in runs})
    nys = sorted({r["ny"] for r in runs})
    out.append("| mesh | tets | nodes | h | " + " | ".join(f"w/w_EB, nu = {nu:g}" for nu in poissons)
               + f" | solve {COST_LABEL[COST]} (nu = " + f"{poissons[len(poissons) // 2]:g}) |")
    out.append("|---|---|---|---|" + "---|" * len(poissons) + "---|")
    for ny in nys:
        sel = {r["poisson"]: r for r in runs if r["ny"] == ny}
        first = next(iter(sel.values()))
        cells = []
        for nu in poissons:
            r = sel.get(nu)
            cells.append("-" if not r or r["status"] != "ok" else f"{r['w_fem'] / r['w_eb']:.3f} ({100 * r['rel_error']:+.1f} %)")
        mid = sel.get(poissons[len(poissons) // 2])
        out.append(f"| {first['mesh']} | {first['tets']} | {first['nodes']} | {1e3 * first['h']:.2f} mm | "
                   + " | ".join(cells) + f" | {fmt_time(cost(mid)) if mid else '-'} |")
    # Observed order and limit from the three finest meshes: w(h) = w0 + C h^p.
    notes = []
    for nu in poissons:
        sel = sorted((r for r in runs if r["poisson"] == nu and r["status"] == "ok"), key=lambda r: r["h"])
        if len(sel) < 3:
            continue
        h = [r["h"] for r in sel[:3]]
        w = [r["w_fem"] for r in sel[:3]]
        fit = richardson(h, w)
        w_eb, w_t = sel[0]["w_eb"], sel[0]["w_timoshenko"]
        if fit and fit[0] >= 1.2:
            p, w0 = fit
            notes.append(f"nu = {nu:g}: observed order {p:.2f} on the three finest meshes; extrapolated "
                         f"h -> 0 limit w/w_EB = {w0 / w_eb:.3f} (Timoshenko beam with shear: {w_t / w_eb:.3f}); "
                         f"finest mesh {100 * (w[0] - w0) / w0:+.1f} % from that limit")
        else:
            order = f" (observed order {fit[0]:.2f})" if fit else ""
            notes.append(f"nu = {nu:g}: not yet in the asymptotic range on these meshes{order}; linear tets lock "
                         f"as nu grows, the finest mesh is still {100 * (w[0] - w_eb) / w_eb:+.1f} % off w_EB")
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    for nu, marker in zip(poissons, "osD^v"):
        sel = sorted((r for r in runs if r["poisson"] == nu and r["status"] == "ok"), key=lambda r: r["h"])
        ax.loglog([1e3 * r["h"] for r in sel], [abs(r["rel_error"]) for r in sel], marker=marker,
                  label=f"linear tets, nu = {nu:g}")
    h = np.array(sorted({r["h"] for r in runs}))
    anchor = min(abs(r["rel_error"]) for r in runs if r["ny"] == max(nys))
    guide = h[h <= 3.0 * h.min()]
    ax.loglog(1e3 * guide, anchor * (guide / h.min()) ** 2, "k--", linewidth=1, label="slope 2")
    ax.set_xticks(1e3 * h)
    ax.set_xticklabels([f"{1e3 * v:.3g}" for v in h])
    ax.minorticks_off()
    ax.set_xlabel("element size h = a / ny (mm)")
    ax.set_ylabel("|w_fem - w_EB| / w_EB at the tip")
    ax.set_title("Static tip load: linear tets against Euler-Bernoulli F L^3 / (3 E I)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "static_eb.png"), dpi=110)
    plt.close(fig)
    return "static_eb.png", notes


def static_nonlinear(rows, out, outdir):
    runs = study(rows, "static_nonlinear")
    if not runs:
        return None
    materials = [m for m in MATERIALS if m != "linear" and any(r["material"] == m for r in runs)]
    loads = sorted({r["w_linear_over_L"] for r in runs})
    mesh = runs[0]["mesh"]
    out.append(f"| linear tip deflection / L | tip load | " + " | ".join(f"{m}: w/w_linear - 1 (Newton its)" for m in materials) + " |")
    out.append("|---|---|" + "---|" * len(materials))
    for load_ratio in loads:
        cells = []
        force = None
        for m in materials:
            r = next((r for r in runs if r["material"] == m and r["w_linear_over_L"] == load_ratio), None)
            if r is None:
                cells.append("-")
                continue
            force = r["load_N"]
            if r["status"] != "ok":
                cells.append(f"{r['status']} ({r['iterations']})")
            else:
                cells.append(f"{100 * r['rel_diff']:+.2f} % ({r['iterations']})")
        out.append(f"| {100 * load_ratio:g} % | {1e3 * force:.3g} mN | " + " | ".join(cells) + " |")
    crossings = []
    for m in materials:
        sel = sorted((r for r in runs if r["material"] == m and r["status"] == "ok"), key=lambda r: r["w_linear_over_L"])
        for level in (0.01, 0.05, 0.10):
            x = None
            for a, b in zip(sel, sel[1:]):
                da, db = abs(a["rel_diff"]), abs(b["rel_diff"])
                if da < level <= db:  # log-log interpolation
                    t = (math.log(level) - math.log(da)) / (math.log(db) - math.log(da))
                    x = math.exp(math.log(a["w_linear_over_L"]) + t * (math.log(b["w_linear_over_L"]) - math.log(a["w_linear_over_L"])))
                    break
            crossings.append((m, level, x))
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    for m, marker in zip(materials, "osD^"):
        sel = sorted((r for r in runs if r["material"] == m and r["status"] == "ok"), key=lambda r: r["w_linear_over_L"])
        ax.loglog([100 * r["w_linear_over_L"] for r in sel], [100 * abs(r["rel_diff"]) for r in sel], marker=marker,
                  label=m)
        failed = [r for r in runs if r["material"] == m and r["status"] != "ok"]
        if failed:
            ax.scatter([100 * r["w_linear_over_L"] for r in failed], [30.0] * len(failed), marker="x", s=60,
                       label=f"{m}: Newton not converged")
    for level in (1.0, 5.0):
        ax.axhline(level, color="grey", linestyle="--", linewidth=1)
    ax.set_xlabel("linear tip deflection / L (%)")
    ax.set_ylabel("|w_nonlinear - w_linear| / w_linear (%)")
    ax.set_title(f"Static tip load, {mesh} bar: nonlinear against linear elasticity")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "static_nonlinear.png"), dpi=110)
    plt.close(fig)
    return "static_nonlinear.png", crossings


# ------------------------------------------------------------------------------------------------


def main():
    global COST
    args = sys.argv[1:]
    if "--cost" in args:
        k = args.index("--cost")
        if k + 1 >= len(args) or args[k + 1] not in COST_LABEL:
            sys.exit("report.py: --cost cpu|wall")
        COST = args[k + 1]
        del args[k:k + 2]
    if len(args) != 2:
        sys.exit("usage: report.py ACCURACY.jsonl OUTDIR [--cost cpu|wall]")
    path, outdir = args
    os.makedirs(outdir, exist_ok=True)
    rows = load(path)
    meta = next((r for r in rows if r.get("study") == "meta"), {})
    meta_end = next((r for r in rows if r.get("study") == "meta_end"), {})

    md = []
    md.append("# softhap: error against run time")
    md.append("")
    md.append(f"Generated by `make report` (`softhap_bench accuracy > {os.path.basename(path)}`, then "
              f"`scripts/report.py`) from {os.path.basename(path)}. Library version {meta.get('version', '?')}, "
              f"CHOLMOD {'on' if meta.get('cholmod') else 'off'}; the run took "
              f"{meta_end.get('total_wall_s', float('nan')):.0f} s in {meta.get('jobs', 1)} worker process(es); "
              f"load average {meta.get('loadavg_before', float('nan')):.1f} before and "
              f"{meta_end.get('loadavg_after', float('nan')):.1f} after on this 2-core machine. **Cost** = "
              f"{COST_LABEL[COST]} of each run's step loop"
              + (" (the library runs on one thread, so this is the run's wall time on an idle core; the wall "
                 "times in the JSON lines are inflated, unevenly, by the other processes that shared the machine)"
                 if COST == "cpu" else "") + ".")
    md.append("")
    md.append("## Setup")
    md.append("")
    E = meta.get("young_Pa")
    md.append(f"- **Bar**: {1e3 * meta.get('length_m', 0):g} x {1e3 * meta.get('side_m', 0):g} x "
              f"{1e3 * meta.get('side_m', 0):g} mm, cubes of 6 tets (Kuhn split), nx = 10 ny; E = {E:g} Pa, "
              f"nu = {meta.get('poisson')}, rho = {meta.get('density'):g} kg/m^3; clamped at x = 0 "
              "(`sh_body_fix_nodes`).")
    md.append(f"- **Dynamic**: released from rest under gravity -z, compared at t = {meta.get('end_time')} s. "
              "error = max over nodes |x - x_ref| / max over nodes |x_ref - X| (the reference's tip displacement). "
              "Explicit methods run under `SH_UNSTABLE_REJECT` (never sub-stepped) at dt = dt_crit 2^(-k/2) from "
              "their own dt_crit (`sh_body_info.dt_critical`, sqrt 2 larger for RK4) downwards; a run rolled back "
              "as unstable is listed as such. Implicit Euler runs at dt = 0.5 s / (10 2^j), with one Newton "
              f"iteration (linearised, Baraff-Witkin) and with Newton to {meta.get('newton_tolerance'):g}. "
              f"**Reference**: RK4 on the same mesh and material at a step {meta.get('reference_factor')}x smaller "
              "than the smallest explicit step of the sweep; the same RK4 reference serves the implicit rows "
              "(it is far more accurate than an implicit-Euler reference could be).")
    md.append(f"- **Damping**: every body, every method: Rayleigh alpha = {meta.get('damping_mass')} 1/s "
              f"(`damping_mass`) and beta = {meta.get('damping_stiffness'):g} s (`damping_stiffness`). Mass damping "
              "alone does not make forward Euler or RK2 usable: forward Euler grows every mode with omega dt > "
              "alpha / omega, i.e. it needs dt < alpha / omega_max^2 (far below dt_crit for any alpha that leaves "
              "the bending motion alone), whereas with stiffness damping it needs dt < beta, independent of the "
              "mode. beta damps the bending modes by a ratio beta omega / 2 < 0.1 %; it also lowers dt_crit "
              "(the library accounts for it).")
    md.append(f"- **Cost**: {COST_LABEL[COST]} around the step loop (clock_gettime "
              f"{'CLOCK_PROCESS_CPUTIME_ID, OMP_NUM_THREADS=1' if COST == 'cpu' else 'CLOCK_MONOTONIC'}; explicit "
              "steps with report NULL, implicit steps with a report for the Newton counts); wall and CPU time are "
              "both in the JSON lines (`wall_s`, `cpu_s`).")
    md.append("")

    summary_lines = []
    table_lines = []
    summary, meshes = dynamic_tables(rows, None, table_lines)
    if meshes:
        ny, mesh = meshes[-1]
        md.append(f"## Summary: {COST_LABEL[COST]} to reach 1 % / 0.1 % error at t = 0.5 s, mesh {mesh}")
        md.append("")
        summary_table(summary, ny, mesh, summary_lines)
        md.extend(summary_lines)
        md.append("")
        md.append("Observations (computed from the runs below):")
        md.append("")
        observations(rows, summary, meshes, md)
        md.append("")
        md.append("## Dynamic: cheapest setting per method")
        md.append("")
        md.append(f"Cheapest run (smallest {COST_LABEL[COST]}) whose error at t = 0.5 s is at most 1 % and 0.1 %; "
                  "order = least-squares slope of log error against log dt over the three smallest stable steps; unstable = runs rolled back "
                  "(forward Euler above dt ~ beta).")
        md.append("")
        md.extend(table_lines)
        md.append("")
        md.append("Reference runs (the RK4 error floor estimate is the finest swept RK4 error scaled by "
                  "(dt_ref / dt)^4; errors near 1e-12 are round-off):")
        md.append("")
        reference_table(rows, md)
        md.append("")
        plots = dynamic_plots(rows, meshes, outdir)
        for name in plots:
            md.append(f"![{name}]({name})")
            md.append("")

    osc_lines = []
    osc_plot = oscillator(rows, osc_lines, outdir)
    if osc_plot:
        md.append("## 1-DOF oscillator: orders")
        md.append("")
        md.append(f"Spring body: node 0 fixed, node 1 of 1 kg on k = 25 N/m (omega = {meta.get('osc_omega'):g} rad/s), "
                  "released from 0.1 m stretch, no damping, no gravity. error = |(x - x_exact, (v - v_exact) / "
                  f"omega)| / amplitude at t = {meta.get('osc_end_time'):g} s; dt = 1/8 .. 1/8192 s. Measured order = "
                  "slope over the points with error in [1e-11, 5e-2].")
        md.append("")
        md.extend(osc_lines)
        md.append("")
        md.append(f"![{osc_plot}]({osc_plot})")
        md.append("")

    eb_lines = []
    eb = static_eb(rows, eb_lines, outdir)
    if eb:
        name, notes = eb
        force = next(r["load_N"] for r in study(rows, "static_eb"))
        md.append("## Static: linear tets against Euler-Bernoulli")
        md.append("")
        md.append(f"Gravity off, linear elasticity, tip load F = {1e3 * force:.3g} mN (consistent nodal loads of a "
                  "uniform traction on the tip face) so that Euler-Bernoulli gives w = F L^3 / (3 E I) = L / 100 "
                  "(I = a^4 / 12); w_fem = load-weighted mean z displacement of the tip face; one sparse solve "
                  "(`sh_world_solve_static`). Linear tets are too stiff in bending (shear locking), so coarse meshes "
                  "are far off: that is the discretisation error this table measures. The limit is not exactly "
                  "w_EB either: shear deformation (Timoshenko) and the clamp's restraint of the Poisson contraction "
                  "differ from beam theory by about 1 %.")
        md.append("")
        md.extend(eb_lines)
        md.append("")
        for note in notes:
            md.append(f"- {note}")
        md.append("")
        md.append(f"![{name}]({name})")
        md.append("")

    nl_lines = []
    nl = static_nonlinear(rows, nl_lines, outdir)
    if nl:
        name, crossings = nl
        md.append("## Static: nonlinear materials against linear elasticity as the load grows")
        md.append("")
        md.append("Same bar and tip load (dead load, -z), nu = 0.3, mesh as in the table, loads increasing with "
                  "Newton continuation from the previous equilibrium (2 load steps, line search). The linear "
                  "answer is exactly proportional to the load; the nonlinear ones stiffen geometrically (the tip "
                  "swings inwards and rotates, the load's lever arm shrinks).")
        md.append("")
        md.extend(nl_lines)
        md.append("")
        for m in sorted({c[0] for c in crossings}, key=MATERIALS.index):
            parts = []
            for mm, level, x in crossings:
                if mm == m:
                    parts.append(f"{100 * level:g} % at w_linear/L = {100 * x:.1f} %" if x else f"{100 * level:g} % not reached")
            md.append(f"- {m}: differs from linear by " + "; ".join(parts))
        md.append("")
        md.append(f"![{name}]({name})")
        md.append("")

    with open(os.path.join(outdir, "accuracy.md"), "w") as f:
        f.write("\n".join(md))
    print(f"report.py: wrote {os.path.join(outdir, 'accuracy.md')}", file=sys.stderr)


if __name__ == "__main__":
    main()
