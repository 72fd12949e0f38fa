#!/usr/bin/python3
"""Crash trials (issue 47; docs/robustness.md): kill -9 at seeded moments, then --restart.

Each trial starts a small `granagg md` run and SIGKILLs it several times, each time at a moment
drawn from a seeded generator, continuing it with `granagg md --restart` after each kill. Three
kinds of moment take turns:
  h5write     the K-th write of the trajectory's HDF5 driver (GRANAGG_FAULT=kill:h5write:K, see
              common/FaultInjection.h): inside a frame, an observables block or a flush;
  checkpoint  half-way through writing the K-th checkpoint (GRANAGG_FAULT=kill:checkpoint:K);
  wall        a SIGKILL from outside after a random wall-clock delay.
After the last kill the run is continued to its end. Then:
  - the run finished (exit 0) and `granagg analyze` reads it;
  - its traj.h5 has the frame steps and times of an uninterrupted run with the same seed, and
    every frame's positions, velocities, charges and images, bit for bit.
The file each kill left is also opened as it was, before any repair, to count the kills that
would have lost the trajectory without the undo journal (common/H5Journal.h): that count is
reported, not asserted (it depends on where HDF5 happens to be when the kill comes).

A failing trial prints its seed and moments, so `--only N` replays it. Exit 0 when all pass.
With --lammps, a few trials of granagg-lammps on 2 MPI ranks follow (the kill lands on rank 0,
the writer; mpirun then ends the other rank, as a node failure would).
"""
import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np

RUN = ["--preset", "quick", "--set", "system.N=1000", "--set", "run.t_end=30",
       "--set", "output.frame_interval=0.5", "--set", "output.checkpoint_interval=200",
       "--set", "system.seed=7"]
KINDS = ("h5write", "checkpoint", "wall")


def run(cmd, env=None, timeout=300):
    e = dict(os.environ)
    e.pop("GRANAGG_FAULT", None)
    e.update(env or {})
    return subprocess.run(cmd, env=e, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, timeout=timeout)


def kill_leftovers(folder):
    """SIGKILLs every process whose command line names `folder` (the MPI ranks that outlive a
    killed mpirun, which a node failure would take with it) and waits until none is left."""
    for _ in range(200):
        left = []
        for pid in filter(str.isdigit, os.listdir("/proc")):
            try:
                with open(f"/proc/{pid}/cmdline", "rb") as f:
                    argv = f.read().split(b"\0")
            except OSError:
                continue
            if folder.encode() in argv and int(pid) != os.getpid():
                left.append(int(pid))
        if not left:
            return
        for pid in left:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        time.sleep(0.05)


def run_killed_after(cmd, delay):
    """Starts cmd, SIGKILLs it after `delay` seconds unless it ended; returns (rc, output)."""
    e = dict(os.environ)
    e.pop("GRANAGG_FAULT", None)
    p = subprocess.Popen(cmd, env=e, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         start_new_session=True)
    try:
        out, _ = p.communicate(timeout=delay)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        kill_leftovers(cmd[cmd.index("--out") + 1] if "--out" in cmd else cmd[-1])
    return p.returncode, out


def passages(launch, site, work):
    """How often the uninterrupted run passes the fault point `site`."""
    d = os.path.join(work, "count-" + site)
    shutil.rmtree(d, ignore_errors=True)
    r = run(launch + ["md"] + RUN + ["--out", d], {"GRANAGG_FAULT": f"count:{site}:1"})
    for line in r.stdout.splitlines():
        if line.startswith(f"granagg: fault point {site} passed"):
            return int(line.split()[5])
    sys.exit(f"crash_trials: no passage count for {site}:\n{r.stdout}")


def raw_readable(path):
    """Whether the file a kill left opens and yields its last complete frame, unrepaired."""
    try:
        with h5py.File(path, "r") as f:
            p = f["particles/all/position"]
            n = min(p["value"].shape[0], p["step"].shape[0], p["time"].shape[0])
            if n > 0:
                p["value"][n - 1]
                f["particles/all/velocity/value"][n - 1]
            return True
    except Exception:  # noqa: BLE001 (any failure to read counts)
        return False


def compare(ref, got):
    """'' when got/traj.h5 equals ref/traj.h5 frame for frame, bit for bit; else the difference."""
    with h5py.File(os.path.join(ref, "traj.h5"), "r") as a, \
         h5py.File(os.path.join(got, "traj.h5"), "r") as b:
        for name in ("position/step", "position/time", "position/value", "velocity/value",
                     "charge/value", "image/value"):
            x = a["particles/all/" + name][()]
            y = b["particles/all/" + name][()]
            if x.shape != y.shape:
                return f"{name}: shape {y.shape}, uninterrupted {x.shape}"
            if x.tobytes() != y.tobytes():
                bad = np.argwhere(x != y)
                return f"{name}: {len(bad)} elements differ, first at {bad[0].tolist()}"
    return ""


def trial(args, launch, ref, index, kind, budget, wall_ref):
    rng = random.Random(args.seed * 1000 + index)
    d = os.path.join(args.work, f"{'lammps' if launch != [args.granagg] else 'md'}-{index}")
    shutil.rmtree(d, ignore_errors=True)
    fresh = launch + ["md"] + RUN + ["--out", d]
    restart = launch + ["md", "--restart", d]
    if launch != [args.granagg]:  # granagg-lammps takes the options without the `md` verb
        fresh = [x for x in fresh if x != "md"]
        restart = [x for x in restart if x != "md"]
    log, kills, torn, repairs = [], 0, 0, 0
    cmd = fresh
    for k in range(args.kills):
        if kind == "wall":
            delay = rng.uniform(0.02, wall_ref)
            rc, out = run_killed_after(cmd, delay)
            moment = f"wall {delay:.3f} s"
        else:
            K = rng.randint(1, max(1, budget // 2))
            r = run(cmd, {"GRANAGG_FAULT": f"kill:{kind}:{K}"})
            rc, out = r.returncode, r.stdout
            moment = f"{kind} K={K}"
        if rc == 0:  # the run ended before the moment came
            log.append(moment + ": not reached")
            cmd = restart  # (a finished run: --restart has nothing to do)
            break
        if rc not in (-signal.SIGKILL, 128 + signal.SIGKILL) and launch == [args.granagg]:
            return False, log + [f"{moment}: exit {rc}, not a kill:\n{out}"], kills, torn
        kills += 1
        repairs += out.count("rolled back the unfinished write")
        traj = os.path.join(d, "traj.h5")
        if os.path.exists(traj):
            shutil.copyfile(traj, os.path.join(args.work, "raw.h5"))
            if not raw_readable(os.path.join(args.work, "raw.h5")):
                torn += 1
                moment += " (traj.h5 unreadable as the kill left it)"
        if any(os.path.exists(os.path.join(d, c)) for c in ("checkpoint.h5", "checkpoint.toml")):
            cmd = restart
        else:  # killed before the first checkpoint: --restart must say so and how to start again
            r = run(restart)
            # (the hint to start again needs traj.h5: a kill before it was created left nothing)
            hint = ("start it again with its command and --force"
                    if os.path.exists(traj) else "no checkpoint at")
            if r.returncode != 2 or hint not in r.stdout:
                return False, log + [f"{moment}: --restart without a checkpoint gave exit "
                                     f"{r.returncode}:\n{r.stdout}"], kills, torn
            moment += " (before the first checkpoint: started again with --force)"
            cmd = fresh + ["--force"]
        log.append(moment)
    # the last command to its end, without a fault
    r = run(cmd)
    if r.returncode != 0:
        return False, log + [f"final continuation: exit {r.returncode}\n{r.stdout}"], kills, torn
    repairs += r.stdout.count("rolled back the unfinished write")
    a = run([args.granagg, "analyze", d, "--out", os.path.join(d, "analysis"), "--quiet"])
    if a.returncode != 0:
        return False, log + [f"granagg analyze: exit {a.returncode}\n{a.stdout}"], kills, torn
    diff = compare(ref, d)
    if diff:
        return False, log + ["trajectory differs from the uninterrupted run: " + diff], kills, torn
    shutil.rmtree(d, ignore_errors=True)
    return True, log + [f"{repairs} restarts rolled back a torn write"], kills, torn


def disk_trials(args, ref):
    """A full disk: writes fail with ENOSPC from the K-th on (the fault hook, in the trajectory or
    in a checkpoint), or with EFBIG past a file-size limit (RLIMIT_FSIZE, as `ulimit -f` sets;
    granagg ignores SIGXFSZ). Each run must stop with one error line that says how to continue,
    release its folder, and then continue to the uninterrupted run's trajectory, bit for bit."""
    import resource
    rng = random.Random(args.seed)
    failures = 0
    cases = [("enospc", "h5write"), ("enospc", "checkpoint"), ("fsize", None)] * 2
    for i, (how, site) in enumerate(cases):
        d = os.path.join(args.work, f"disk-{i}")
        shutil.rmtree(d, ignore_errors=True)
        fresh = [args.granagg, "md"] + RUN + ["--out", d]
        if how == "enospc":
            K = rng.randint(2, max(2, args.budget[site] // 2))
            moment = f"ENOSPC from {site} K={K}"
            r = run(fresh, {"GRANAGG_FAULT": f"enospc:{site}:{K}"})
        else:
            limit = rng.randint(400_000, 3_000_000)
            moment = f"file-size limit {limit} B"
            e = dict(os.environ)
            e.pop("GRANAGG_FAULT", None)

            def limited(limit=limit):
                resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))
            r = subprocess.run(fresh, env=e, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, timeout=300, preexec_fn=limited)
        errors = [ln for ln in r.stdout.splitlines() if ln.startswith("granagg: failed")]
        problem = ""
        if r.returncode != 1 or len(errors) != 1:
            problem = f"exit {r.returncode} with {len(errors)} error lines"
        elif "granagg md --restart " + d not in errors[0]:
            problem = "the error line does not say how to continue: " + errors[0]
        elif os.path.exists(os.path.join(d, ".granagg.lock")):
            problem = "the folder lock was left behind"
        if not problem:
            c = run([args.granagg, "md", "--restart", d])
            if "no checkpoint at" in c.stdout:
                c = run(fresh + ["--force"])
            if c.returncode != 0:
                problem = f"the continuation failed (exit {c.returncode}):\n{c.stdout}"
            else:
                problem = compare(ref, d)
        ok = not problem
        failures += not ok
        print(f"{'ok  ' if ok else 'FAIL'} disk trial {i} (seed {args.seed}): {moment}: "
              + (errors[0] if ok and errors else problem), flush=True)
        if ok:
            shutil.rmtree(d, ignore_errors=True)
    failures += tmpfs_trials(args, ref, rng)
    print(f"crash_trials disk: {len(cases)} trials, {failures} failed", flush=True)
    return failures


def tmpfs_trials(args, ref, rng):
    """A real full disk: the run goes into a tmpfs smaller than its folder would grow (0.3-0.9 of
    the uninterrupted run's folder, so that the trajectory, its journal or a checkpoint's
    temporary file fills it). It must stop with exit status 1 and one line that names the file
    and says the disk is full; the folder, copied to a larger disk, must continue to the
    uninterrupted run, bit for bit. Needs mount (root, as in CI); skipped with a note otherwise."""
    full = sum(os.path.getsize(os.path.join(ref, f)) for f in os.listdir(ref))
    mnt = os.path.join(args.work, "tmpfs")
    os.makedirs(mnt, exist_ok=True)
    failures = 0
    for i in range(2):
        size = int(full * rng.uniform(0.3, 0.9)) // 4096 * 4096
        m = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", mnt],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if m.returncode != 0:
            print("skip tmpfs trials: cannot mount a tmpfs here (" + m.stdout.strip() + ")",
                  flush=True)
            return failures
        try:
            d = os.path.join(mnt, "run")
            r = run([args.granagg, "md"] + RUN + ["--out", d])
            errors = [ln for ln in r.stdout.splitlines() if ln.startswith("granagg: failed")]
            problem = ""
            if r.returncode != 1 or len(errors) != 1:
                problem = f"exit {r.returncode} with {len(errors)} error lines:\n{r.stdout}"
            elif "the disk is full" not in errors[0] or d not in errors[0]:
                problem = "the error line does not name the file and the full disk: " + errors[0]
            elif any(f.endswith(".tmp") for f in os.listdir(d)):
                problem = "a temporary file was left: " + " ".join(os.listdir(d))
            copy = os.path.join(args.work, f"tmpfs-copy-{i}")
            shutil.rmtree(copy, ignore_errors=True)
            if not problem:
                shutil.copytree(d, copy)
        finally:
            subprocess.run(["umount", mnt])
        if not problem:
            c = run([args.granagg, "md", "--restart", copy])
            if "no checkpoint at" in c.stdout:
                c = run([args.granagg, "md"] + RUN + ["--out", copy, "--force"])
            problem = (f"the continuation failed (exit {c.returncode}):\n{c.stdout}"
                       if c.returncode != 0 else compare(ref, copy))
        ok = not problem
        failures += not ok
        print(f"{'ok  ' if ok else 'FAIL'} tmpfs trial {i}: a tmpfs of {size} B "
              f"({size / full:.2f} of the run's folder): " + (errors[0] if ok else problem),
              flush=True)
        if ok:
            shutil.rmtree(copy, ignore_errors=True)
    print(f"crash_trials tmpfs: 2 trials, {failures} failed", flush=True)
    return failures


def campaign(args, launch, label, trials, first_index):
    ref = os.path.join(args.work, f"ref-{label}")
    shutil.rmtree(ref, ignore_errors=True)
    cmd = launch + ["md"] + RUN + ["--out", ref]
    if label != "md":
        cmd = [x for x in cmd if x != "md"]
    t0 = time.time()
    r = run(cmd)
    wall_ref = time.time() - t0
    if r.returncode != 0:
        sys.exit(f"crash_trials: the uninterrupted {label} run failed:\n{r.stdout}")
    budget = {"h5write": passages(launch, "h5write", args.work) if label == "md" else 0,
              "checkpoint": passages(launch, "checkpoint", args.work) if label == "md" else 0}
    if label != "md":  # the counts of `granagg md` on the same run (same frames and checkpoints)
        budget = args.budget
    else:
        args.budget = budget
    failures = total_kills = total_torn = 0
    counts = {k: 0 for k in KINDS}
    for i in range(first_index, first_index + trials):
        if args.only is not None and i != args.only:
            continue
        # (granagg-lammps writes its checkpoint through LAMMPS: no checkpoint fault point)
        kinds = KINDS if label == "md" else ("h5write", "wall")
        kind = kinds[i % len(kinds)]
        ok, log, kills, torn = trial(args, launch, ref, i, kind, budget.get(kind, 0), wall_ref)
        total_kills += kills
        total_torn += torn
        counts[kind] += kills
        status = "ok  " if ok else "FAIL"
        print(f"{status} {label} trial {i} (seed {args.seed}, {kind}): " + "; ".join(log),
              flush=True)
        failures += not ok
    print(f"crash_trials {label}: {trials} trials, {total_kills} kills "
          f"({', '.join(f'{counts[k]} {k}' for k in KINDS)}), {failures} failed; "
          f"{total_torn} kills left a traj.h5 that HDF5 could not read before the journal's "
          f"rollback", flush=True)
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--granagg", required=True)
    ap.add_argument("--lammps", help="granagg-lammps binary (its trials run on 2 ranks)")
    ap.add_argument("--mpiexec", default="mpirun")
    ap.add_argument("--work", required=True)
    ap.add_argument("--trials", type=int, default=24)
    ap.add_argument("--lammps-trials", type=int, default=3)
    ap.add_argument("--kills", type=int, default=3, help="kills per trial")
    ap.add_argument("--seed", type=int, default=47)
    ap.add_argument("--only", type=int, help="replay one trial")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    failures = campaign(args, [args.granagg], "md", args.trials, 0)
    if args.only is None:
        failures += disk_trials(args, os.path.join(args.work, "ref-md"))
    if args.lammps:
        mpi = [args.mpiexec, "--oversubscribe", "-np", "2"]
        if os.geteuid() == 0:
            mpi.append("--allow-run-as-root")
        failures += campaign(args, mpi + [args.lammps], "lammps", args.lammps_trials,
                             args.trials)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
