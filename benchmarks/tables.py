"""Markdown tables from a run.py report (also: python benchmarks/tables.py results/latest.json)."""

from __future__ import annotations

import json
import statistics
import sys

KNOB = {"exudyn": "h", "exudyn-fast": "h", "mujoco": "timestep"}  # every casmech tool: rtol
PEERS = ("exudyn", "exudyn-fast", "mujoco", "casadi-script")


def _setting(tool: str, setting: dict | None) -> str:
    if not setting:
        return ""
    tool = tool.partition("@")[0]
    knob = "rtol" if tool.startswith("casmech") or tool == "casadi-script" else KNOB[tool]
    return f"{knob}={setting[knob]:g}"


def _seconds(x: float) -> str:
    if x >= 100:
        return f"{x:.0f}"
    if x >= 1:
        return f"{x:.2f}"
    return f"{x:.3g}"


def _load(values) -> str:
    return ", ".join(f"{v:.2f}" for v in values) if values else "?"


def _note(result: dict) -> str:
    extra = result.get("extra", {})
    notes = []
    if "projections" in extra:
        notes.append(f"{extra['projections']} projections")
    if "loop_violation" in extra:
        notes.append(f"loop gap {extra['loop_violation']:.1e} m")
    status = result.get("status", "ok")
    if status == "stopped":
        notes.append(f"stopped after {result['seconds']:.0f} s (slower than "
                     f"{result['limit']:.0f} s: pruned)")
    elif status == "timeout":
        notes.append(f"timed out after {result['seconds']:.0f} s (--timeout)")
    elif status in ("error", "skipped"):
        notes.append(f"{status}: {result.get('message', '')}")
    return "; ".join(notes)


def best_at(results: list[dict], tool: str, level: float, key: str = "median"):
    """The fastest setting of `tool` (by `key`: "median" wall or "cpu_median") within
    `level`."""
    ok = [r for r in results if r["tool"] == tool and key in r and r["error"] <= level]
    return min(ok, key=lambda r: r[key]) if ok else None


def t_end(report: dict) -> str:
    """The simulated span every timed run covered (run.py --t-end; 10 s before it existed)."""
    return f"{report.get('settings', {}).get('t_end', 10.0):g} s"


def sweep_table(entry: dict, span: str = "10 s") -> list[str]:
    lines = [f"| tool | setting | wall, {span} [s] (median) | n | min - max [s] | error at 1 s [m] "
             "| note |", "|---|---|---:|---:|---|---:|---|"]
    for r in entry["results"]:
        tool = r["tool"]
        if "median" in r:
            walls = r["walls"]
            lines.append(f"| {tool} | {_setting(tool, r.get('setting'))} | "
                         f"{_seconds(r['median'])} | {len(walls)} | "
                         f"{_seconds(min(walls))} - {_seconds(max(walls))} | "
                         f"{r['error']:.1e} | {_note(r)} |")
        else:
            lines.append(f"| {tool} | {_setting(tool, r.get('setting'))} | - | 0 | | | "
                         f"{_note(r)} |")
    return lines


def level_table(entry: dict, levels, tools: list[str], key: str = "median") -> list[str]:
    peers = [t for t in tools if t in PEERS]
    ours = [t for t in tools if t.startswith("casmech")]
    pairs = [(c, p) for c in ours for p in peers]
    head = "| error <= | " + " | ".join(tools) + " | " + " | ".join(
        f"{c} / {p}" for c, p in pairs) + " |"
    lines = [head, "|---|" + "---|" * (len(tools) + len(pairs))]
    for level in levels:
        best = {t: best_at(entry["results"], t, level, key) for t in tools}
        cells = []
        for t in tools:
            b = best[t]
            if b is None:
                reached = [r["error"] for r in entry["results"] if r["tool"] == t and "error" in r]
                cells.append("not reached" + (f" (best {min(reached):.0e})" if reached else ""))
            else:
                cells.append(f"{_seconds(b[key])} s ({_setting(t, b['setting'])})")
        ratios = []
        for ours_tool, p in pairs:
            c, b = best.get(ours_tool), best[p]
            ratios.append(f"{c[key] / b[key]:.3g}" if c and b else "-")
        lines.append(f"| {level:g} m | " + " | ".join(cells) + " | " + " | ".join(ratios) + " |")
    return lines


def build_table(report: dict, tools: list[str]) -> list[str]:
    lines = ["| system | " + " | ".join(tools) + " |", "|---|" + "---|" * len(tools)]
    for entry in report["systems"]:
        cells = []
        for t in tools:
            parts = [r["build"]["parts"] for r in entry["results"]
                     if r["tool"] == t and "build" in r]
            if not parts:
                cells.append("-")
            elif t.startswith("casmech"):
                load = statistics.median(p["load"] for p in parts)
                comp = statistics.median(p["compile"] for p in parts)
                cells.append(f"{_seconds(load + comp)} s (load {_seconds(load)} + compile "
                             f"{_seconds(comp)})")
            else:
                key = "compile" if t in ("mujoco", "casadi-script") else "build"
                cells.append(f"{_seconds(statistics.median(p[key] for p in parts))} s")
        lines.append(f"| {entry['system']} | " + " | ".join(cells) + " |")
    return lines


def cross_table(report: dict) -> list[str]:
    lines = ["| system | reference (planar, RK4, step halving) | tool, tightest setting, to "
             "t = 1 s | distance from the reference [m] |", "|---|---|---|---:|"]
    for entry in report["systems"]:
        ref = entry["reference"]
        first = True
        for r in entry["cross_check"] or [{}]:
            loop = (f", loop residual {ref['loop_residual']:.0e} m" if ref["loop_residual"]
                    else "")
            head = (f"| {entry['system']} | h = {ref['step']:g} s, last halving "
                    f"{ref['agreement']:.0e} m{loop}, {ref['seconds']:.1f} s | ") if first \
                else "| | | "
            first = False
            if not r:
                lines.append(head + "(not run) | |")
                continue
            value = f"{r['error']:.1e}" if "error" in r else r.get("status", "")
            lines.append(head + f"{r['tool']} {_setting(r['tool'], r['setting'])} | {value} |")
    return lines


def _verdict(new: list[float], old: list[float]) -> str:
    """Beyond noise only where the two commits' runs do not overlap at all."""
    if min(new) > max(old):
        return "**slower**"
    if max(new) < min(old):
        return "faster"
    return "within noise"


def commit_sweep(report: dict, commits: list[str], bases: list[str], key: str,
                 samples: str, what: str) -> list[str]:
    """Time to each accuracy and every setting, each commit against the first, by `key`."""
    old = commits[0]
    if not any(key in r for entry in report["systems"] for r in entry["results"]):
        return []
    out = [f"Time to an accuracy by {what} time: the fastest setting of each commit that "
           "reaches it.", "",
           "| system | tool | error <= | " + " | ".join(f"@{c}" for c in commits) + " | "
           + " | ".join(f"@{c} / @{old}" for c in commits[1:]) + " |",
           "|---|---|---|" + "---|" * (2 * len(commits) - 1)]
    for entry in report["systems"]:
        for b in bases:
            for level in report["levels"]:
                best = [best_at(entry["results"], f"{b}@{c}", level, key) for c in commits]
                cells = [f"{_seconds(x[key])} s ({_setting(b, x['setting'])})" if x
                         else "not reached" for x in best]
                ratios = [f"{x[key] / best[0][key]:.3g}" if x and best[0] else "-"
                          for x in best[1:]]
                out.append(f"| {entry['system']} | {b} | {level:g} m | " + " | ".join(cells)
                           + " | " + " | ".join(ratios) + " |")
    out += ["", f"Every setting by {what} time: median [min - max] of each commit; a difference "
            "is beyond noise only where the two commits' runs do not overlap.", "",
            "| system | tool | setting | " + " | ".join(f"@{c}" for c in commits) + " | "
            + " | ".join(f"@{c} / @{old} | verdict" for c in commits[1:]) + " |",
            "|---|---|---|" + "---|" * (len(commits) + 2 * (len(commits) - 1))]
    for entry in report["systems"]:
        for b in bases:
            runs = {c: [r for r in entry["results"] if r["tool"] == f"{b}@{c}"]
                    for c in commits}
            for k, first in enumerate(runs[old]):
                row = [runs[c][k] if k < len(runs[c]) else {} for c in commits]
                cells = [f"{_seconds(r[key])} [{_seconds(min(r[samples]))} - "
                         f"{_seconds(max(r[samples]))}]" if key in r
                         else r.get("status", "-") for r in row]
                ratios = []
                for r in row[1:]:
                    if key in r and key in first:
                        ratios.append(f"{r[key] / first[key]:.3g} | "
                                      f"{_verdict(r[samples], first[samples])}")
                    else:
                        ratios.append("- | -")
                out.append(f"| {entry['system']} | {b} | {_setting(b, first.get('setting'))} | "
                           + " | ".join(cells) + " | " + " | ".join(ratios) + " |")
    return out + [""]


def commit_tables(report: dict, tools: list[str]) -> list[str]:
    """Each later commit against the first (run.py --casmech-commit with several commits)."""
    commits = report["machine"].get("commits") or []
    if len(commits) < 2:
        return []
    old = commits[0]
    bases = list(dict.fromkeys(t.partition("@")[0] for t in tools if "@" in t))
    out = [f"### Each commit against {old} (new / old: below 1 the later commit is faster)", ""]
    for key, samples, what in (("median", "walls", "wall"), ("cpu_median", "cpus", "CPU")):
        out += commit_sweep(report, commits, bases, key, samples, what)
    out += ["Build (load + compile, median over the setting's processes):", "",
            "| system | tool | " + " | ".join(f"@{c}" for c in commits) + " | "
            + " | ".join(f"@{c} / @{old}" for c in commits[1:]) + " |",
            "|---|---|" + "---|" * (2 * len(commits) - 1)]
    for entry in report["systems"]:
        for b in bases:
            times = []
            for c in commits:
                parts = [r["build"]["parts"] for r in entry["results"]
                         if r["tool"] == f"{b}@{c}" and "build" in r]
                times.append(statistics.median(p["load"] + p["compile"] for p in parts)
                             if parts else None)
            cells = [f"{_seconds(x)} s" if x is not None else "-" for x in times]
            ratios = [f"{x / times[0]:.3g}" if x is not None and times[0] else "-"
                      for x in times[1:]]
            out.append(f"| {entry['system']} | {b} | " + " | ".join(cells) + " | "
                       + " | ".join(ratios) + " |")
    return out + [""]


def markdown(report: dict) -> str:
    tools = []
    for entry in report["systems"]:
        for r in entry["results"]:
            if r["tool"] not in tools:
                tools.append(r["tool"])
    m = report["machine"]
    out = [f"Run of {m['date']} on {m.get('Model name', '?')} ({m.get('CPU(s)', '?')} CPUs), "
           f"Python {m['python']}, casadi {m.get('casadi')}, exudyn {m.get('exudyn')}, "
           f"mujoco {m.get('mujoco')}, numpy {m.get('numpy')}, scipy {m.get('scipy')}; "
           f"casmech: {m.get('casmech_source')}; repository HEAD {m.get('git_commit', '?')[:10]}"
           f"{' (src/ modified)' if m.get('src_dirty') else ''}; imported from "
           f"{m.get('casmech_file')}. BLAS threads per worker: "
           f"{report.get('settings', {}).get('threads', '?')}. Load average (1, 5, 15 min) "
           "at start "
           f"{_load(m.get('loadavg_start'))}, at end {_load(m.get('loadavg_end'))}.",
           "", f"Command: `{report['command']}`", ""]
    out += ["### Time to reach an accuracy (fastest measured setting; wall time of the "
            f"{t_end(report)} simulation, median)", "",
            "casmech / peer is the ratio of wall times: below 1 casmech is faster.", ""]
    for entry in report["systems"]:
        out += [f"**{entry['system']}** ({entry['description']})", ""]
        out += level_table(entry, report["levels"], tools) + [""]
        if any("cpu_median" in r for r in entry["results"]):
            out += ["The same by the CPU time of each run (its process's user + system time "
                    "over the same span; steadier than wall time on a loaded machine):", ""]
            out += level_table(entry, report["levels"], tools, "cpu_median") + [""]
    out += commit_tables(report, tools)
    out += ["### Model build / compile time (median over the setting's processes)", ""]
    out += build_table(report, tools) + [""]
    out += ["### Reference and cross-check", ""] + cross_table(report) + [""]
    out += ["### Every setting", ""]
    for entry in report["systems"]:
        out += [f"**{entry['system']}**", ""] + sweep_table(entry, t_end(report)) + [""]
    return "\n".join(out)


if __name__ == "__main__":
    print(markdown(json.loads(open(sys.argv[1]).read())))
