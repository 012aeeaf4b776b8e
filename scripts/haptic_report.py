#!/usr/bin/env python3
"""Error against run time for haptics: turn the `softhap_bench haptic*` JSON lines into a report.

    python3 scripts/haptic_report.py report/

reads, in that folder,
  haptic_cost.jsonl    softhap_bench haptic --rt         (cost against buffer size)
  haptic_error.jsonl   softhap_bench haptic-error        (force error against buffer radius)
  haptic_force.jsonl   softhap_bench haptic-force        (force smoothness, VBM against ZOH)
  haptic_force.csv     its per-tick trace (--csv)
and writes haptic.md (tables) and the plots
  haptic_cost.png      median and p99.9 of the haptic step against buffer tets, with the peers
  haptic_error.png     force error against buffer radius and against the step's median time
  haptic_force.png     the press-and-slide force trace: VBM rendered against the full model's ZOH

The peers' costs are quoted (measured once on this machine class with MuJoCo's flex and NVIDIA
Newton/Warp on the CPU), not measured by this script. Needs numpy and matplotlib (`make haptic-report` installs matplotlib when it is missing).
"""
import csv
import json
import os
import sys

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

# Quoted, not measured here (see the docstring): fixed cost (us) + cost per tet (us) of one step.
PEERS = [
    ("MuJoCo flex (quoted)", 13.0, 0.140, "tab:purple"),
    ("NVIDIA Newton/Warp on CPU (quoted)", 52.0, 0.037, "tab:brown"),
]
# The haptic step's goals: a 500-tet buffer within these times.
GOAL_TETS = 500
GOAL_MEDIAN_US = 20.0
GOAL_P999_US = 40.0
GOAL_OVERHEAD_NS = 1000.0

MATERIALS = ["corotational", "linear", "stvk", "neohookean"]


def load(path):
    rows = []
    if not os.path.exists(path):
        return rows
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line.startswith("{"):
                continue
            try:
                rows.append(json.loads(line))
            except json.JSONDecodeError as e:
                sys.exit(f"haptic_report.py: {path}:{number}: not JSON ({e})")
    return rows


def study(rows, name):
    return [r for r in rows if r.get("study") == name]


def env_text(rows, what):
    env = study(rows, "haptic_env")
    if not env:
        return f"{what}: no environment line"
    e = env[-1]
    rt = "the haptic thread SCHED_FIFO" if e.get("rt") else "normal scheduling"
    return (f"{what}: {e['seconds']:.0f} s, load average {e['load_before']:.1f} before and {e['load_after']:.1f} "
            f"after on this 2-core machine, {rt}")


def peer_us(fixed, per_tet, tets):
    return fixed + per_tet * tets


def fmt_us(x):
    if x is None:
        return "-"
    return f"{x:.1f}" if x < 1000 else f"{x:.0f}"


def pct(x):
    return f"{100 * x:.3g} %"


def verdict(ok):
    return "met" if ok else "**not met**"


# ------------------------------------------------------------------------------------------------
# Cost


def cost_section(rows, out, folder):
    frozen = sorted(study(rows, "haptic_cost"), key=lambda r: r["buffer_tets"])
    rate = [r for r in frozen if "/rate/" in r["case"]]
    main = [r for r in frozen if r["sim"] == "frozen" and r["material"] == "corotational" and r not in rate]
    sim = [r for r in frozen if r["sim"] == "sim"]
    overhead = study(rows, "haptic_overhead")
    out.append("## Cost against buffer size")
    out.append("")
    out.append(env_text(rows, "Run") + ". Every step is timed on its own (`CLOCK_MONOTONIC`); percentiles over "
               "all timed steps of a case. The machine's 2 cores are shared with other work, so the tails (p99.9, "
               "max) include time the hypervisor or other processes took; the medians are stable to a few %.")
    out.append("")
    out.append("Scene (bench/haptic.c): a 6 x 6 x 3 cm block, 5184 tets (5 mm cells, Kuhn split), base fixed, "
               "E = 15 kPa, nu = 0.45, rho = 1000 kg/m^3; a sphere tool (r = 1 cm, Hunt-Crossley 1e4 N/m^1.5, "
               "n = 1.5) pressed 3 mm into the top centre, then circling 1 mm once a second; 1 kHz haptic step. The "
               "buffer holds the N tets nearest the contact point (`capacity_tets` = N, radius 1 m). The world does "
               "not step while the steps are timed (\"frozen\"), except in the concurrent table. A counting "
               "allocator (`sh_set_allocator`, installed before anything is created) counts the calls from the "
               "haptic thread during the timed loop.")
    out.append("")
    if main:
        out.append("### Corotational (the headline), world not stepping")
        out.append("")
        peer_heads = " | ".join(f"{p[0]}: us" for p in PEERS)
        out.append(f"| buffer tets | nodes | steps | median us | p99 us | p99.9 us | max us | sub-steps | ns/tet "
                   f"| ns/(tet sub-step) | allocations | {peer_heads} |")
        out.append("|---|---|---|---|---|---|---|---|---|---|---|" + "---|" * len(PEERS))
        for r in main:
            peers = " | ".join(fmt_us(peer_us(p[1], p[2], r["buffer_tets"])) for p in PEERS)
            out.append(f"| {r['buffer_tets']} | {r['buffer_nodes']} | {r['steps']} | {fmt_us(r['median_us'])} "
                       f"| {fmt_us(r['p99_us'])} | {fmt_us(r['p999_us'])} | {fmt_us(r['max_us'])} "
                       f"| {r['substeps_median']:g} | {r['ns_per_tet']:.0f} | {r['ns_per_tet_substep']:.1f} "
                       f"| {r['allocations']} | {peers} |")
        out.append("")
    if rate:
        out.append("### Against the device's rate and the tool's stiffness (corotational, world not stepping)")
        out.append("")
        out.append("\"soft\": the default sphere (1e4 N/m^1.5); \"stiff\": 2e5 N/m^1.5. The sub-steps follow the "
                   "elements alone (the contact is implicit in the buffer's step).")
        out.append("")
        out.append("| case | buffer tets | steps | median us | p99.9 us | sub-steps | allocations |")
        out.append("|---|---|---|---|---|---|---|")
        for r in sorted(rate, key=lambda r: (r["dt"], r["tool_stiffness"], r["buffer_tets"])):
            out.append(f"| {r['case']} | {r['buffer_tets']} | {r['steps']} | {fmt_us(r['median_us'])} "
                       f"| {fmt_us(r['p999_us'])} | {r['substeps_median']:g} | {r['allocations']} |")
        out.append("")
        at = [r for r in main if r["buffer_tets"] == GOAL_TETS]
        if at:
            r = at[0]
            out.append(f"Goals at {GOAL_TETS} tets: median <= {GOAL_MEDIAN_US:g} us: "
                       f"{fmt_us(r['median_us'])} us, {verdict(r['median_us'] <= GOAL_MEDIAN_US)}; p99.9 <= "
                       f"{GOAL_P999_US:g} us: {fmt_us(r['p999_us'])} us, {verdict(r['p999_us'] <= GOAL_P999_US)}. The "
                       f"step takes {r['substeps_median']:g} explicit sub-steps of the buffer per 1 ms (the critical "
                       f"step of its elements; the contact is implicit); per tet and sub-step it costs "
                       f"{r['ns_per_tet_substep']:.0f} ns. The peers' columns are the quoted fixed + per-tet "
                       "costs, evaluated at the same tet counts (not measured here, and not necessarily at the same "
                       "number of sub-steps).")
            out.append("")
        fit = np.polyfit([r["buffer_tets"] for r in main], [r["median_us"] for r in main], 1)
        out.append(f"Least-squares line through the medians: {fit[1]:.1f} us + {fit[0] * 1e3:.0f} ns per tet "
                   "(MuJoCo flex, quoted: 13 us + 140 ns per tet; Newton/Warp CPU, quoted: 52 us + 37 ns per tet).")
        out.append("")
    if overhead:
        r = overhead[-1]
        out.append("### Fixed overhead")
        out.append("")
        out.append("The tool 1 m above the block: the buffer is empty and the step renders the untouched proxy "
                   "plane (pose checks, triple-buffer hand-over, force filter).")
        out.append("")
        out.append("| per call: median ns | p99 ns | p99.9 ns | batches of 100 calls: median ns per call | clock read ns "
                   "| allocations |")
        out.append("|---|---|---|---|---|---|")
        out.append(f"| {r['median_ns']:.0f} | {r['p99_ns']:.0f} | {r['p999_ns']:.0f} | {r['batch_median_ns']:.0f} "
                   f"| {r['clock_ns']:.0f} | {r['allocations']} |")
        out.append("")
        out.append(f"Goal < {GOAL_OVERHEAD_NS:g} ns: {verdict(r['batch_median_ns'] < GOAL_OVERHEAD_NS)} (the per-call "
                   "median includes one clock read).")
        out.append("")
    others = [m for m in MATERIALS if any(r["material"] == m and r["sim"] == "frozen" for r in frozen)]
    if len(others) > 1:
        sizes = sorted({r["capacity_tets"] for r in frozen if r["sim"] == "frozen"})
        out.append("### Median step time by material (us), world not stepping")
        out.append("")
        out.append("| material | " + " | ".join(f"{n} tets" for n in sizes) + " | ns/(tet sub-step) at 500 | p99.9 at 500 |")
        out.append("|---|" + "---|" * len(sizes) + "---|---|")
        for m in others:
            by = {r["capacity_tets"]: r for r in frozen if r["sim"] == "frozen" and r["material"] == m}
            at = by.get(GOAL_TETS)
            tail = f" | {at['ns_per_tet_substep']:.1f} | {fmt_us(at['p999_us'])} |" if at else " | - | - |"
            out.append(f"| {m} | " + " | ".join(fmt_us(by[n]["median_us"]) if n in by else "-" for n in sizes) + tail)
        out.append("")
    if sim:
        out.append("### Corotational, with a sim thread stepping the world concurrently")
        out.append("")
        out.append("A second thread (pinned to the other core, ordinary scheduling) steps the world by 1/60 s "
                   "(implicit Euler) at most 60 times per second; each step moves the full model's tool to the "
                   "device pose and re-extracts the buffer, which the haptic side adopts. The haptic thread runs "
                   "paced at 1 kHz of wall time.")
        out.append("")
        out.append("| buffer tets | steps | median us | p99 us | p99.9 us | max us | sub-steps | allocations "
                   "| sim rate (target 60 Hz) | sim step median ms | fresh buffers taken |")
        out.append("|---|---|---|---|---|---|---|---|---|---|---|")
        for r in sim:
            out.append(f"| {r['buffer_tets']} | {r['steps']} | {fmt_us(r['median_us'])} | {fmt_us(r['p99_us'])} "
                       f"| {fmt_us(r['p999_us'])} | {fmt_us(r['max_us'])} | {r['substeps_median']:g} "
                       f"| {r['allocations']} | {r['sim_rate_hz']:.1f} Hz | {r['sim_step_median_ms']:.1f} "
                       f"| {r['fresh_buffers']} |")
        out.append("")
    if main:
        cost_plot(main, sim, frozen, os.path.join(folder, "haptic_cost.png"))
        out.append("![cost](haptic_cost.png)")
        out.append("")


def cost_plot(main, sim, frozen, path):
    fig, ax = plt.subplots(figsize=(7.5, 5.2))
    tets = np.array([r["buffer_tets"] for r in main], dtype=float)
    ax.loglog(tets, [r["median_us"] for r in main], "o-", color="tab:blue", label="softhap corotational: median")
    ax.loglog(tets, [r["p999_us"] for r in main], "o--", color="tab:blue", alpha=0.6,
              label="softhap corotational: p99.9")
    if sim:
        ax.loglog([r["buffer_tets"] for r in sim], [r["median_us"] for r in sim], "s:", color="tab:cyan",
                  label="corotational beside a sim thread: median")
    for m, colour in (("linear", "tab:green"), ("neohookean", "tab:orange"), ("stvk", "tab:olive")):
        sel = sorted((r for r in frozen if r["sim"] == "frozen" and r["material"] == m), key=lambda r: r["buffer_tets"])
        if sel:
            ax.loglog([r["buffer_tets"] for r in sel], [r["median_us"] for r in sel], ".-", color=colour, alpha=0.7,
                      label=f"softhap {m}: median")
    span = np.geomspace(tets.min(), tets.max(), 50)
    for name, fixed, per_tet, colour in PEERS:
        ax.loglog(span, peer_us(fixed, per_tet, span), "-", color=colour, alpha=0.5, linewidth=2, label=name)
    ax.plot([GOAL_TETS], [GOAL_MEDIAN_US], "k*", markersize=12, label=f"goal: median {GOAL_MEDIAN_US:g} us at {GOAL_TETS}")
    ax.plot([GOAL_TETS], [GOAL_P999_US], "kx", markersize=10, label=f"goal: p99.9 {GOAL_P999_US:g} us at {GOAL_TETS}")
    ax.set_xlabel("tets in the buffer")
    ax.set_ylabel("haptic step time (us)")
    ax.set_title("sh_haptic_step cost against buffer size (1 kHz step, 2 shared cores)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ------------------------------------------------------------------------------------------------
# Error


def error_section(rows, out, folder):
    refs = {r["mesh"]: r for r in study(rows, "haptic_error_reference")}
    runs = study(rows, "haptic_error")
    if not runs:
        return
    out.append("## Force error against buffer radius")
    out.append("")
    out.append(env_text(rows, "Run") + ".")
    out.append("")
    out.append("The liver lies on its flattest side with its lowest 10 % fixed (no gravity: the press is the only "
               "load), corotational, E = 15 kPa, nu = 0.45, scaled to 16 cm; the sphere tool (r = 1 cm) presses "
               "8 mm into the centre of the largest nearly level facet of its top. **Reference**: the full model "
               "solved statically with the tool at the same pose (`sh_world_solve_static`, tolerance 1e-9, then "
               "`sh_tool_get_wrench`). **VBM**: the haptic context presses over 0.3 s and holds to 3 s at 1 kHz "
               "(mass damping 100 1/s, no force clamp, rate limit nor ramp); its `raw_force` at 3 s is compared: "
               "error = |F_vbm - F_ref| / |F_ref|. **frozen**: the world does not step, so the buffer's boundary "
               "stays where the full model was before the press (the full model has not reacted: the VBM's "
               "truncation error). **coupled**: the world steps by 1/60 s every 1/60 s of haptic time (implicit "
               "Euler, interleaved on one thread), so the boundary follows the full model. Step time: median over "
               "the last 2000 ticks.")
    out.append("")
    for mesh in sorted({r["mesh"] for r in runs}):
        ref = refs.get(mesh)
        if ref:
            f = ref["force"]
            out.append(f"**{mesh}** ({ref['mesh_tets']} tets, {ref['fixed_nodes']} fixed nodes): reference force "
                       f"({f[0]:.3f}, {f[1]:.3f}, {f[2]:.3f}) N, {ref['contact_count']} contact point(s), static "
                       f"solve {ref['iterations']} Newton iterations, {'converged' if ref['converged'] else 'NOT converged'}.")
            out.append("")
        frozen = sorted((r for r in runs if r["mesh"] == mesh and r["mode"] == "frozen"), key=lambda r: r["radius_m"])
        coupled = {r["radius_m"]: r for r in runs if r["mesh"] == mesh and r["mode"] == "coupled"}
        out.append("| radius | buffer tets (frozen) | frozen: error | frozen: z error (signed) | frozen: median us "
                   "| sub-steps | coupled: buffer tets | coupled: error | coupled: median us | settled (change over "
                   "the last 0.5 s) |")
        out.append("|---|---|---|---|---|---|---|---|---|---|")
        for r in frozen:
            c = coupled.get(r["radius_m"])
            radius = "1 m (whole organ)" if r["radius_m"] >= 1.0 else f"{r['radius_m'] * 100:g} cm"
            settle = max(r["settle_change"], c["settle_change"] if c else 0.0)
            out.append(f"| {radius} | {r['buffer_tets']} | {pct(r['rel_error'])} "
                       f"| {100 * r['rel_error_normal']:+.3g} % | {fmt_us(r['median_us'])} "
                       f"| {r['substeps_median']:g} | {c['buffer_tets'] if c else '-'} "
                       f"| {pct(c['rel_error']) if c else '-'} | {fmt_us(c['median_us']) if c else '-'} "
                       f"| {settle:.1e} |")
        out.append("")
    error_plot(runs, os.path.join(folder, "haptic_error.png"))
    out.append("![error](haptic_error.png)")
    out.append("")


def error_plot(runs, path):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    colours = {"liver": "tab:blue", "liver2": "tab:red"}
    for mesh in sorted({r["mesh"] for r in runs}):
        for mode, style in (("frozen", "o-"), ("coupled", "s--")):
            sel = sorted((r for r in runs if r["mesh"] == mesh and r["mode"] == mode), key=lambda r: r["radius_m"])
            if not sel:
                continue
            err = [max(r["rel_error"], 1e-9) for r in sel]
            label = f"{mesh} ({sel[-1]['mesh_tets']} tets), {mode}"
            radii = [min(r["radius_m"], 0.2) * 100 for r in sel]  # the whole organ plotted at 20 cm
            axes[0].semilogy(radii, err, style, color=colours.get(mesh), label=label, alpha=0.85)
            axes[1].loglog([r["median_us"] for r in sel], err, style, color=colours.get(mesh), label=label, alpha=0.85)
            for r in sel:
                axes[1].annotate(str(r["buffer_tets"]), (r["median_us"], max(r["rel_error"], 1e-9)), fontsize=6,
                                 textcoords="offset points", xytext=(3, 3), color=colours.get(mesh))
    axes[0].set_xlabel("buffer radius (cm; 20 = the whole organ, radius 1 m)")
    axes[0].set_ylabel("|F_vbm - F_static| / |F_static|")
    axes[0].set_title("error against buffer radius (settled press, 8 mm)")
    axes[1].set_xlabel("median haptic step time (us)")
    axes[1].set_title("error against step time (labels: buffer tets)")
    axes[1].xaxis.set_major_locator(matplotlib.ticker.FixedLocator([5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000]))
    axes[1].xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    axes[1].xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ------------------------------------------------------------------------------------------------
# Force smoothness


def read_trace(path):
    if not os.path.exists(path):
        return None
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def force_section(rows, out, folder):
    signals = {r["signal"]: r for r in study(rows, "haptic_force")}
    run = study(rows, "haptic_force_run")
    if not signals or not run:
        return
    run = run[-1]
    out.append("## Force smoothness: VBM against a zero-order hold of the full model")
    out.append("")
    out.append(env_text(rows, "Run") + ".")
    out.append("")
    out.append(f"The same set-up on {run['mesh']} (mass damping 2 1/s), one thread, deterministic: a haptic tick "
               "every 1 ms of haptic time (buffer radius 3 cm, default force limits: 10 N, 2000 N/s, 50 ms ramp) "
               "and a full-model step (implicit Euler) every 1/60 s of it. The tool approaches from 5 mm above the "
               "touching height (0-0.3 s), presses 8 mm (0.3-0.8 s), holds, slides 3 cm at that depth following the "
               "top (1.0-2.5 s), holds, lifts off (2.7-3.2 s). **ZOH**: `sh_tool_get_wrench` after each full-model "
               "step, held for the next 16.7 ms (what a host without the VBM would render). |dF| = |F(i) - F(i-1)| "
               "per 1 ms tick.")
    out.append("")
    labels = {"vbm": "VBM, rendered (`force`)", "vbm_raw": "VBM, raw (`raw_force`)", "zoh": "full model, ZOH at 60 Hz"}
    out.append("| signal | max abs(dF) per tick, N | RMS abs(dF), N | slide: max abs(dF), N | slide: RMS abs(dF), N | peak abs(F), N |")
    out.append("|---|---|---|---|---|---|")
    for key in ("vbm", "vbm_raw", "zoh"):
        s = signals.get(key)
        if s:
            out.append(f"| {labels[key]} | {s['max_dF_N']:.3g} | {s['rms_dF_N']:.3g} | {s['max_dF_slide_N']:.3g} "
                       f"| {s['rms_dF_slide_N']:.3g} | {s['peak_N']:.3g} |")
    out.append("")
    out.append(f"Haptic step in this run: median {run['median_us']:.1f} us, p99.9 {run['p999_us']:.0f} us, "
               f"{run['mean_buffer_tets']:.0f} buffer tets on average, {run['allocations']} allocations; full-model "
               f"step median {run['sim_step_median_ms']:.1f} ms ({run['sim_steps']} steps, {run.get('sim_failed', 0)} "
               "not converged).")
    out.append("")
    trace = read_trace(os.path.join(folder, "haptic_force.csv"))
    if trace is not None:
        where = []
        for key, label in (("vbm", "VBM"), ("zoh", "ZOH")):
            f = np.stack([trace[f"{key}_x"], trace[f"{key}_y"], trace[f"{key}_z"]], axis=1)
            d = np.linalg.norm(np.diff(f, axis=0), axis=1)
            i = int(np.argmax(d)) + 1
            where.append(f"{label} {d[i - 1]:.3g} N at t = {trace['t'][i]:.3f} s ({f[i - 1][2]:.3g} -> {f[i][2]:.3g} N "
                         "along z)")
        out.append("Largest tick-to-tick change: " + "; ".join(where) + ".")
        out.append("")
        force_plot(trace, os.path.join(folder, "haptic_force.png"))
        out.append("![force](haptic_force.png)")
        out.append("")


def force_plot(t, path):
    fig, axes = plt.subplots(3, 1, figsize=(10, 8.5), sharex=True)
    time = t["t"]
    axes[0].plot(time, t["zoh_z"], color="tab:red", label="full model, ZOH at 60 Hz")
    axes[0].plot(time, t["vbm_z"], color="tab:blue", label="VBM rendered (1 kHz)")
    axes[0].set_ylabel("F_z (N)")
    lateral = {k: np.hypot(t[f"{k}_x"], t[f"{k}_y"]) for k in ("vbm", "zoh")}
    axes[1].plot(time, lateral["zoh"], color="tab:red", label="full model, ZOH")
    axes[1].plot(time, lateral["vbm"], color="tab:blue", label="VBM rendered")
    axes[1].set_ylabel("|F_xy| (N)")
    for key, colour, label in (("zoh", "tab:red", "ZOH"), ("vbm", "tab:blue", "VBM rendered")):
        f = np.stack([t[f"{key}_x"], t[f"{key}_y"], t[f"{key}_z"]], axis=1)
        d = np.linalg.norm(np.diff(f, axis=0), axis=1)
        axes[2].semilogy(time[1:], np.maximum(d, 1e-6), ".", markersize=2, color=colour, label=label, alpha=0.6)
    axes[2].set_ylabel("|dF| per 1 ms tick (N)")
    axes[2].set_ylim(1e-5, None)
    axes[2].set_xlabel("time (s)")
    for ax in axes:
        for edge in (0.3, 0.8, 1.0, 2.5, 2.7, 3.2):
            ax.axvline(edge, color="0.8", linewidth=0.8)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[0].set_title("press (0.3-0.8 s), slide 3 cm (1.0-2.5 s), lift (2.7-3.2 s): VBM against ZOH")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: haptic_report.py REPORT_FOLDER")
    folder = sys.argv[1]
    cost = load(os.path.join(folder, "haptic_cost.jsonl"))
    error = load(os.path.join(folder, "haptic_error.jsonl"))
    force = load(os.path.join(folder, "haptic_force.jsonl"))
    if not (cost or error or force):
        sys.exit(f"haptic_report.py: no haptic_*.jsonl in {folder}")
    out = ["# softhap: haptic step cost, error and smoothness", "",
           "Generated by `make haptic-report` (`softhap_bench haptic --rt`, `haptic-error` and `haptic-force --csv`, "
           "then `scripts/haptic_report.py`) from haptic_cost.jsonl, haptic_error.jsonl, haptic_force.jsonl and "
           "haptic_force.csv. The peers' figures are quoted, not measured here.", ""]
    cost_section(cost, out, folder)
    error_section(error, out, folder)
    force_section(force, out, folder)
    with open(os.path.join(folder, "haptic.md"), "w") as f:
        f.write("\n".join(out))
    print(f"wrote {os.path.join(folder, 'haptic.md')}")


if __name__ == "__main__":
    main()
