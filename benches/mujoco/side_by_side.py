#!/usr/bin/env python3
"""quadsim against MuJoCo, side by side, on this machine.

MuJoCo steps the shared quad16 model (`quad16.xml` beside this script, a
copy of the project's `shared/models/quad16.xml`: dt 0.5 ms, PD position servos holding the standing pose, four foot
contacts), the issue's reference; quadsim runs `quadsim bench --robots 1
--threads 1` (one quad16 trotting at 0.5 m/s under VMC, the full closed-loop
step), with the controller on the estimate (sensors and estimator, the
default) and on the exact state (`--sensing ground-truth`). The two run in
alternating rounds in one process tree, so that a loaded or throttled
machine slows both alike; the ratio MuJoCo µs / quadsim µs is quadsim's step
rate in multiples of MuJoCo's (the issue's target: at least 3).

With `--herd N` (e.g. 256) each round also measures both on two cores:
MuJoCo as two processes stepping a quad16 each at once (its robot-steps/s
and its speedup over one process: what the machine's two cores give an
independent single-threaded job), and `quadsim bench --robots N --threads
1,2` (robot-steps/s on two threads and the speedup over one).

    python3 -m venv .venv && .venv/bin/pip install -r benches/mujoco/requirements.txt
    cargo build --release
    .venv/bin/python benches/mujoco/side_by_side.py [--rounds 3] [--steps 4000]

Prints one line per round and, last, one line of JSON with every figure.
Wall-clock figures: medians of blocks, single thread.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def mujoco_us_per_step(model_path: Path, steps: int, blocks: int) -> tuple[float, int]:
    """Median wall time of one `mj_step` (µs) over `blocks` blocks of `steps`
    steps, after 1 s of settling onto the feet; and the contacts then."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(model_path))
    d = mujoco.MjData(m)
    mujoco.mj_resetData(m, d)
    if m.nkey:
        mujoco.mj_resetDataKeyframe(m, d, 0)
    settle = int(round(1.0 / m.opt.timestep))
    mujoco.mj_step(m, d, nstep=settle)
    times = []
    for _ in range(blocks):
        t0 = time.perf_counter()
        mujoco.mj_step(m, d, nstep=steps)
        times.append((time.perf_counter() - t0) / steps * 1e6)
    return statistics.median(times), int(d.ncon)


def _mujoco_worker(args: tuple[str, int, int]) -> float:
    return mujoco_us_per_step(Path(args[0]), args[1], args[2])[0]


def mujoco_two_processes(model_path: Path, steps: int, blocks: int) -> tuple[float, float]:
    """Two processes step a quad16 each at the same time: (robot-steps/s of
    both together, speedup over one process alone measured just before)."""
    import multiprocessing

    one = _mujoco_worker((str(model_path), steps, blocks))
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        both = pool.map(_mujoco_worker, [(str(model_path), steps, blocks)] * 2)
    rate = sum(1e6 / us for us in both)
    return rate, rate / (1e6 / one)


def quadsim_herd(exe: Path, robots: int, steps: int, blocks: int) -> tuple[float, float]:
    """`quadsim bench --robots N --threads 1,2`: (robot-steps/s on 2 threads, speedup over 1)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.json"
        subprocess.run(
            [str(exe), "bench", "--robots", str(robots), "--threads", "1,2", "--steps",
             str(steps), "--repeats", str(blocks), "--json", str(out)],
            check=True, stdout=subprocess.DEVNULL,
        )
        points = {p["threads"]: p for p in json.loads(out.read_text())["points"]}
    two = points[2]["robot_steps_per_s"]
    return two, two / points[1]["robot_steps_per_s"]


def quadsim_us_per_step(exe: Path, steps: int, blocks: int, sensing: str) -> tuple[float, str]:
    """`quadsim bench` for one robot on one thread: µs per step (median block), and the
    build the binary is ("portable" or "cpu": docs/performance.md, "The build for the CPU")."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.json"
        subprocess.run(
            [str(exe), "bench", "--robots", "1", "--threads", "1", "--steps", str(steps),
             "--repeats", str(blocks), "--sensing", sensing, "--json", str(out)],
            check=True, stdout=subprocess.DEVNULL,
        )
        report = json.loads(out.read_text())
    return report["points"][0]["us_per_robot_step"], report.get("build", "unknown")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quadsim", type=Path, default=ROOT / "target/release/quadsim",
                    help="the quadsim binary (default: target/release/quadsim)")
    ap.add_argument("--model", type=Path, default=Path(__file__).with_name("quad16.xml"),
                    help="the MuJoCo model (default: quad16.xml beside this script)")
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds")
    ap.add_argument("--steps", type=int, default=4000, help="steps per timed block")
    ap.add_argument("--blocks", type=int, default=5, help="timed blocks per figure (median)")
    ap.add_argument("--herd", type=int, default=0,
                    help="also compare two cores: MuJoCo in two processes, quadsim with N robots "
                         "on 1 and 2 threads (0: not)")
    ap.add_argument("--herd-steps", type=int, default=400, help="quadsim's steps per block with --herd")
    a = ap.parse_args()
    for path, what in [(a.quadsim, "quadsim binary (cargo build --release)"), (a.model, "MuJoCo model")]:
        if not path.is_file():
            print(f"error: {path}: no {what}", file=sys.stderr)
            return 2
    if a.rounds < 1 or a.steps < 1 or a.blocks < 1:
        print("error: --rounds, --steps and --blocks must be at least 1", file=sys.stderr)
        return 2
    rounds = []
    print(f"{'round':>5} {'MuJoCo µs':>10} {'contacts':>8} {'quadsim µs':>11} {'ratio':>6}"
          f" {'exact-state µs':>14} {'ratio':>6}")
    for r in range(a.rounds):
        mj, ncon = mujoco_us_per_step(a.model, a.steps, a.blocks)
        qs, build = quadsim_us_per_step(a.quadsim, a.steps, a.blocks, "estimated")
        gt, _ = quadsim_us_per_step(a.quadsim, a.steps, a.blocks, "ground-truth")
        rounds.append({"mujoco_us_per_step": mj, "mujoco_contacts": ncon,
                       "quadsim_us_per_step": qs, "quadsim_ground_truth_us_per_step": gt,
                       "ratio": mj / qs, "ratio_ground_truth": mj / gt})
        print(f"{r + 1:>5} {mj:>10.2f} {ncon:>8} {qs:>11.2f} {mj / qs:>5.2f}× {gt:>14.2f} {mj / gt:>5.2f}×")
        if a.herd > 0:
            mj2, mj_speedup = mujoco_two_processes(a.model, a.steps, a.blocks)
            qs2, qs_speedup = quadsim_herd(a.quadsim, a.herd, a.herd_steps, a.blocks)
            rounds[-1].update({"mujoco_two_processes_robot_steps_per_s": mj2,
                               "mujoco_two_processes_speedup": mj_speedup,
                               "quadsim_herd_robots": a.herd,
                               "quadsim_two_threads_robot_steps_per_s": qs2,
                               "quadsim_two_threads_speedup": qs_speedup})
            print(f"      two cores: MuJoCo 2 processes {mj2:,.0f} robot-steps/s ({mj_speedup:.2f}× one);"
                  f" quadsim {a.herd} robots on 2 threads {qs2:,.0f} ({qs_speedup:.2f}× one thread)")
        if ncon != 4:
            print(f"warning: MuJoCo's quad16 has {ncon} contacts, not its four feet", file=sys.stderr)
    ratios = [x["ratio"] for x in rounds]
    print(f"quadsim's step rate / MuJoCo's: {min(ratios):.2f}–{max(ratios):.2f}× "
          f"(median {statistics.median(ratios):.2f}×; target ≥ 3×; quadsim's {build} build)")
    print(json.dumps({"rounds": rounds, "ratio_median": statistics.median(ratios),
                      "quadsim_build": build, "load_average": os.getloadavg()[0]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
