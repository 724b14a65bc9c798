#!/usr/bin/env python3
"""Faults: SIGKILL of either rank at a random moment, then a restart in place.

Run by scripts/fault-check.sh (which builds fdem and sets the MPI
environment). For each case (the N = 50 nut deposition and the two bars,
both on 2 ranks):

1. an uninterrupted reference run, timed (T seconds);
2. KILLS times: start the run (a fresh run, or `--restart` from the
   checkpoint the last killed run left, into the same output directory),
   wait a random time in (0, T), and SIGKILL one of the two ranks chosen at
   random. After each kill the output must be readable: the HDF5 files under
   their final names open (h5dump: the mesh file, every step file, the
   checkpoint), the XDMF index is whole, lists no more steps than there are
   step files, and every dataset it names reads; every history line is whole. A run that finishes before its kill ends a chain: its final state
   must be bitwise the reference's, and the next kill starts a new chain in a
   fresh directory.
3. The last chain is run to the end and compared the same way: every dataset
   of the series (mesh file and step files) and of the checkpoint bitwise
   (h5dump -b), the same step files, the XDMF index and the CSV files byte
   for byte.

Standard library and h5dump only. Exit 1 with the first failure named.
"""
import argparse
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

CASES = {
    "deposit": (
        "scenarios/nut-packing-deposit.toml",
        "nut-packing-deposit",
        ["--set", "bodies.1.pack.count=50", "--set", "output.checkpoint_every=2"],
    ),
    "two-bars": (
        "scenarios/two-bars.toml",
        "two-bars",
        ["--set", "output.checkpoint_every=5000"],
    ),
}


class Failure(Exception):
    pass


def h5dump_ok(args):
    r = subprocess.run(["h5dump"] + args, capture_output=True, text=True)
    return r.returncode == 0, r.stderr.strip()[-400:]


def datasets(h5):
    ok, err = h5dump_ok(["-n", h5])
    if not ok:
        raise Failure("%s: h5dump -n failed: %s" % (h5, err))
    out = subprocess.run(["h5dump", "-n", h5], capture_output=True, text=True).stdout
    return sorted(
        line.split()[1] for line in out.splitlines() if line.strip().startswith("dataset ")
    )


def dataset_bytes(h5, ds, tmp):
    path = os.path.join(tmp, "ds.bin")
    r = subprocess.run(
        ["h5dump", "-d", ds, "-b", "LE", "-o", path, h5], capture_output=True, text=True
    )
    if r.returncode != 0:
        raise Failure("%s: dataset %s does not read: %s" % (h5, ds, r.stderr.strip()[-300:]))
    with open(path, "rb") as f:
        return f.read()


def step_files(d, stem):
    """The step files of the series under their final names (not `.part`)."""
    steps = os.path.join(d, stem + "_steps")
    if not os.path.isdir(steps):
        return []
    return sorted(os.path.join(steps, f) for f in os.listdir(steps) if f.endswith(".h5"))


def check_readable(d, stem, tmp):
    """The output a killed run leaves must be readable as it stands."""
    h5 = os.path.join(d, stem + ".h5")
    xdmf = os.path.join(d, stem + ".xdmf")
    ck = os.path.join(d, stem + "_checkpoint.h5")
    hist = os.path.join(d, stem + "_history.csv")
    steps = step_files(d, stem)
    for f in [h5, ck] + steps:
        if os.path.exists(f):
            ok, err = h5dump_ok(["-H", f])
            if not ok:
                raise Failure("%s does not open after the kill: %s" % (f, err))
    listed = 0
    if os.path.exists(xdmf):
        if not os.path.exists(h5):
            raise Failure("%s lists steps of a missing %s" % (xdmf, h5))
        text = open(xdmf).read()
        if not text.rstrip().endswith("</Xdmf>"):
            raise Failure("%s is truncated" % xdmf)
        listed = len(re.findall(r"<Time Value=", text))
        if listed > len(steps):
            raise Failure("%s lists %d steps, there are %d step files" % (xdmf, listed, len(steps)))
        refs = sorted(set(re.findall(r">([^<>:\s]+\.h5):(/[^<\s]+)<", text)))
        for name, ds in refs:
            f = os.path.join(d, name)
            if not os.path.exists(f):
                raise Failure("%s names the missing %s" % (xdmf, f))
            dataset_bytes(f, ds, tmp)
    if os.path.exists(hist):
        lines = open(hist).read().split("\n")
        if lines and lines[-1] == "":
            lines.pop()
        if lines:
            n = lines[0].count(",")
            for i, line in enumerate(lines[1:], 2):
                if line.count(",") != n:
                    raise Failure("%s line %d is not whole: %r" % (hist, i, line[:80]))
    return listed


def compare_h5(a, b, tmp):
    """Every dataset of `b` bitwise that of `a`, and no other."""
    da, db = datasets(a), datasets(b)
    if da != db:
        raise Failure(
            "%s holds datasets %s, the reference %s" % (b, sorted(set(db) ^ set(da))[:6], "other ones")
        )
    for ds in da:
        if dataset_bytes(a, ds, tmp) != dataset_bytes(b, ds, tmp):
            raise Failure("%s: dataset %s differs from the uninterrupted run's" % (b, ds))


def compare(ref, got, stem, tmp):
    """Bitwise: every dataset of the series and checkpoint, the other files byte for byte."""
    for name in sorted(os.listdir(ref)):
        a, b = os.path.join(ref, name), os.path.join(got, name)
        if not os.path.exists(b):
            raise Failure("%s is missing (the reference has it)" % b)
        if os.path.isdir(a):
            # A series' step files: the same files, each bitwise.
            fa, fb = sorted(os.listdir(a)), sorted(os.listdir(b))
            if fa != fb:
                raise Failure(
                    "%s holds %s, the reference %s" % (b, sorted(set(fa) ^ set(fb))[:6], "other files")
                )
            for f in fa:
                compare_h5(os.path.join(a, f), os.path.join(b, f), tmp)
        elif name.endswith(".h5"):
            compare_h5(a, b, tmp)
        elif not name.endswith(".png"):
            if open(a, "rb").read() != open(b, "rb").read():
                raise Failure("%s differs from the uninterrupted run's" % b)


def start(fdem, scen, out, extra, restart):
    cmd = ["mpirun", "-n", "2", "--oversubscribe", fdem, "run", scen, "--quiet", "--output", out]
    cmd += extra
    if restart:
        cmd += ["--restart", restart]
    return subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def ranks_of(p):
    r = subprocess.run(["pgrep", "-P", str(p.pid), "-x", "fdem"], capture_output=True, text=True)
    return [int(x) for x in r.stdout.split()]


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # A zombie is not running.
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def finish(p, pids, limit=60.0):
    """Wait for mpirun and every rank to be gone (SIGKILL after `limit`)."""
    t0 = time.time()
    while time.time() - t0 < limit:
        if p.poll() is not None and not any(alive(x) for x in pids):
            return p.returncode
        time.sleep(0.05)
    for x in pids:
        if alive(x):
            os.kill(x, signal.SIGKILL)
    p.kill()
    return p.wait()


def run_case(name, fdem, root, kills, rng, tmp):
    scen, stem, extra = CASES[name]
    ref = os.path.join(root, name, "ref")
    shutil.rmtree(os.path.join(root, name), ignore_errors=True)
    os.makedirs(ref)
    t0 = time.time()
    p = start(fdem, scen, ref, extra, None)
    _, err = p.communicate()
    T = time.time() - t0
    if p.returncode != 0:
        raise Failure("%s: the reference run failed: %s" % (name, err[-500:]))
    print("%s: uninterrupted run %.1f s" % (name, T))
    chain, done = 0, 0
    d = None
    while True:
        if d is None:
            chain += 1
            d = os.path.join(root, name, "chain%d" % chain)
            os.makedirs(d)
        ck = os.path.join(d, stem + "_checkpoint.h5")
        restart = ck if os.path.exists(ck) else None
        p = start(fdem, scen, d, extra, restart)
        if done < kills:
            delay = rng.uniform(0.0, T)
            t1 = time.time()
            pids = []
            while time.time() - t1 < delay and p.poll() is None:
                pids = ranks_of(p) or pids
                time.sleep(0.01)
            if p.poll() is None:
                pids = ranks_of(p) or pids
                if len(pids) == 2:
                    victim = rng.randrange(2)
                    try:
                        os.kill(pids[victim], signal.SIGKILL)
                    except ProcessLookupError:
                        pass
                    finish(p, pids)
                    done += 1
                    listed = check_readable(d, stem, tmp)
                    how = "restart" if restart else "fresh run"
                    print(
                        "  kill %2d: %s, rank %d after %.2f s; output readable (%d steps listed)"
                        % (done, how, victim, delay, listed)
                    )
                    continue
                # mpirun has not started both ranks yet: let it be this time.
        _, err = p.communicate()
        if p.returncode != 0:
            raise Failure("%s: the run in %s failed: %s" % (name, d, err[-800:]))
        compare(ref, d, stem, tmp)
        print("  chain %d in %s finished: bitwise the uninterrupted run" % (chain, d))
        d = None
        if done >= kills:
            break
    return done, chain


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fdem", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--kills", type=int, default=20)
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("cases", nargs="*", default=list(CASES))
    a = ap.parse_args()
    seed = a.seed if a.seed is not None else random.SystemRandom().randrange(2**31)
    print("fault-check: seed %d (--seed %d repeats these moments)" % (seed, seed))
    rng = random.Random(seed)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            for name in a.cases:
                done, chains = run_case(name, a.fdem, a.out, a.kills, rng, tmp)
                print("%s: %d kills in %d chain(s), all bitwise" % (name, done, chains))
        except Failure as e:
            print("fault-check: FAIL: %s" % e, file=sys.stderr)
            return 1
    print("fault-check: all passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
