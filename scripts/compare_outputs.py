#!/usr/bin/env python3
"""Compare two sets of fdem outputs written by scripts/compare-outputs.sh.

    compare_outputs.py REF_DIR NEW_DIR [--rtol 1e-10]

For every case directory in REF_DIR, every HDF5 file (series and
checkpoint) must hold the same datasets in NEW_DIR. Temperatures (datasets
whose path names `temperature`, and the checkpoint's heat account) must
agree to --rtol of their largest magnitude (solver tolerance and summation
order); each rank's share of the dissipated energy (how the pair work was
shared, not a result) must agree in its sum; everything else (positions,
displacements, velocities, stresses, mesh, topology) must be bitwise equal.
Standard library and h5dump only.
Exit 1 naming the first difference.
"""
import argparse
import array
import os
import subprocess
import sys
import tempfile

TOLERANT = ("temperature", "account_", "state/scalars")
# Per-rank bookkeeping: how the work was shared, not a result. Only its sum
# must agree (to --rtol).
SUMMED = ("dissipated_per_rank",)


def datasets(h5):
    out = subprocess.run(["h5dump", "-n", h5], check=True, capture_output=True, text=True).stdout
    return sorted(l.split()[1] for l in out.splitlines() if l.strip().startswith("dataset "))


def raw(h5, ds, tmp):
    p = os.path.join(tmp, "d.bin")
    subprocess.run(["h5dump", "-d", ds, "-b", "LE", "-o", p, h5], check=True, capture_output=True)
    with open(p, "rb") as f:
        return f.read()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("ref")
    ap.add_argument("new")
    ap.add_argument("--rtol", type=float, default=1e-10)
    a = ap.parse_args()
    bad = 0
    with tempfile.TemporaryDirectory() as tmp:
        for case in sorted(os.listdir(a.ref)):
            rd, nd = os.path.join(a.ref, case), os.path.join(a.new, case)
            if not os.path.isdir(rd):
                continue
            worst = 0.0
            exact = 0
            for name in sorted(os.listdir(rd)):
                if not name.endswith(".h5"):
                    continue
                ra, na = os.path.join(rd, name), os.path.join(nd, name)
                if not os.path.exists(na):
                    print("%s: %s missing" % (case, na))
                    bad += 1
                    continue
                dr, dn = datasets(ra), datasets(na)
                if dr != dn:
                    print("%s/%s: datasets differ: %s" % (case, name, sorted(set(dr) ^ set(dn))))
                    bad += 1
                    continue
                for ds in dr:
                    x, y = raw(ra, ds, tmp), raw(na, ds, tmp)
                    if any(t in ds for t in SUMMED) and len(x) == len(y) and len(x) % 8 == 0:
                        su, sv = sum(array.array("d", x)), sum(array.array("d", y))
                        if abs(su - sv) > a.rtol * max(abs(su), 1e-300):
                            print("%s/%s %s: sums %.17g and %.17g differ" % (case, name, ds, su, sv))
                            bad += 1
                        else:
                            exact += 1
                    elif any(t in ds for t in TOLERANT) and len(x) == len(y) and len(x) % 8 == 0:
                        u, v = array.array("d", x), array.array("d", y)
                        scale = max([abs(t) for t in u] + [1e-300])
                        diff = max([abs(p - q) for p, q in zip(u, v)] + [0.0]) / scale
                        worst = max(worst, diff)
                        if diff > a.rtol:
                            print("%s/%s %s: relative difference %.3e > %.1e" % (case, name, ds, diff, a.rtol))
                            bad += 1
                    elif x != y:
                        print("%s/%s %s: not bitwise equal" % (case, name, ds))
                        bad += 1
                    else:
                        exact += 1
            print("%-24s %4d datasets bitwise, temperatures within %.2e" % (case, exact, worst))
    if bad:
        print("compare-outputs: %d difference(s)" % bad)
        return 1
    print("compare-outputs: same")
    return 0


if __name__ == "__main__":
    sys.exit(main())
