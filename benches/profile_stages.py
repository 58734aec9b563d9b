#!/usr/bin/env python3
"""Where a robot-step's time (or instructions) goes, by pipeline stage.

Groups a profile's self costs per function into the step's stages with the
rules below (first match wins), so that wall-clock time (perf) and
instructions (callgrind) can be set side by side: code that costs more time
than its share of instructions is latency-bound (libm calls, divisions,
dependent chains, branches), code that costs less runs at a high IPC.

Time, from a timer-sampled perf profile (no hardware counters needed):

    perf record -e cpu-clock -F 999 -o perf.data \\
        target/release/quadsim bench --robots 256 --threads 2 --steps 4000 --repeats 1
    perf report -i perf.data --no-children --sort comm,symbol \\
        | python3 benches/profile_stages.py perf -

Only the simulation pool's threads (`quadsim-sim-*`) are counted, so the
world's construction on the main thread is left out.

Instructions, from two callgrind runs of one robot (1000 and 3000 steps;
their difference is 2000 steps with no start-up in it):

    for s in 1000 3000; do valgrind --tool=callgrind --callgrind-out-file=cg.$s \\
        target/release/quadsim bench --robots 1 --threads 1 --steps $s \\
        --warmup 100 --repeats 1; done
    python3 benches/profile_stages.py callgrind cg.1000 cg.3000
"""

import re
import subprocess
import sys

# (stage, pattern on the function's name), first match wins
RULES = [
    ("dynamics: ABA in lanes", r"aba|Sym6::solve|base_pass1"),
    (
        "dynamics: forward kinematics",
        r"poses|sin_cos|forward_kinematics|base_velocity_at|leg_end_points",
    ),
    (
        "dynamics: contact forces, passive torques, integration",
        r"contact_forces|passive|integrate|quat_from_scaled_axis|clear_external|ForceModel",
    ),
    (
        "libm: atan2, hypot, acos, sincos (leg IK, the QP's rotations, metrics)",
        r"atan2|hypot|acos|sincos|rem_pio2|__cos|__sin|__exp|^floor",
    ),
    ("controller: force QP", r"active_set|force_qp|ForceQp"),
    ("controller: leg IK and Jacobians", r"quad16_leg|quad12_leg|legs::|ik::"),
    ("controller: gait, VMC, feed-forward RNEA, tick", r"walker|gait|vmc|raibert|rnea|control"),
    ("sense: estimator (Kalman update, attitude filter)", r"estimation|kf::|attitude"),
    ("sense: sensors and their noise", r"sensors|noise|chacha|rand|sense|encoders"),
    ("contact: contact update, CoM, observation", r"contact|com::|observe|terrain"),
    (
        "metrics and divergence check",
        r"metrics|Hulls|stability|convex_hull|actuators|divergence|record",
    ),
    ("memcpy, allocator, kernel", r"mem(move|cpy|set)|malloc|free|clear_page|\[k\]"),
]


def stage(name):
    for label, pattern in RULES:
        if re.search(pattern, name, re.I):
            return label
    return "other"


def perf_costs(text):
    """Self percentages per symbol of the pool's threads, from `perf report --sort comm,symbol`."""
    costs = {}
    for line in text.splitlines():
        m = re.match(r"\s*([\d.]+)%\s+(\S+)\s+\[(.)\]\s+(.*?)(\s{2,}|$)", line)
        if not m or not m.group(2).startswith("quadsim-sim"):
            continue
        name = ("[k] " if m.group(3) == "k" else "") + m.group(4).strip()
        costs[name] = costs.get(name, 0.0) + float(m.group(1))
    return costs


def callgrind_self(path):
    out = subprocess.run(
        ["callgrind_annotate", "--inclusive=no", "--auto=no", path],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    costs = {}
    for line in out.splitlines():
        m = re.match(r"\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(\S.*)", line)
        if not m or "PROGRAM TOTALS" in m.group(2):
            continue
        name = m.group(2).split(" [")[0]
        name = name.split(":", 1)[1] if ":" in name else name
        costs[name] = costs.get(name, 0) + int(m.group(1).replace(",", ""))
    return costs


def main(argv):
    if len(argv) == 3 and argv[1] == "perf":
        text = sys.stdin.read() if argv[2] == "-" else open(argv[2]).read()
        costs = perf_costs(text)
        unit = "of the pool's time"
    elif len(argv) == 4 and argv[1] == "callgrind":
        short, long = callgrind_self(argv[2]), callgrind_self(argv[3])
        costs = {k: v - short.get(k, 0) for k, v in long.items()}
        costs = {k: v for k, v in costs.items() if v > 0}
        unit = "of the instructions"
    else:
        sys.exit(__doc__)
    by_stage = {}
    for name, cost in costs.items():
        s = stage(name)
        by_stage[s] = by_stage.get(s, 0) + cost
    total = sum(by_stage.values())
    if total <= 0:
        sys.exit("no samples of the simulation pool's threads found")
    for label, cost in sorted(by_stage.items(), key=lambda kv: -kv[1]):
        print(f"{100 * cost / total:5.1f} %  {label}")
    print(f"(shares {unit})")


if __name__ == "__main__":
    main(sys.argv)
