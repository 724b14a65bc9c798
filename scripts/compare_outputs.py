#!/usr/bin/env python3
"""Compare two sets of fdem outputs written by scripts/compare-outputs.sh.

    compare_outputs.py REF_DIR NEW_DIR [--rtol 1e-10]

For every case directory in REF_DIR, every HDF5 file (a series' mesh file
`<stem>.h5` and its step files `<stem>_steps/*.h5`, and the checkpoint)
must hold the same datasets in NEW_DIR, and a series the same step files. Temperatures (datasets
whose path names `temperature`, and the checkpoint's heat account) must
agree to --rtol of their largest magnitude (solver tolerance and summation
order), and so do all floating-point datasets of the cases named with
--tolerant-case (their motion follows their temperatures); each rank's share of the dissipated energy (how the pair work was
shared, not a result) must agree in its sum; everything else (positions,
displacements, velocities, stresses, mesh, topology) must be bitwise equal,
after the rows of both series are put in global id order (a series written
in the rows of a partition carries each row's node id), so outputs of
different partitions and rank counts compare. The owner rank of each cell
is not compared. Standard library and h5dump only.
Exit 1 naming the first difference.
"""
import argparse
import array
import os
import subprocess
import sys
import tempfile

TOLERANT = ("temperature", "account_", "state/scalars", "state/settled")
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


# Which datasets of a series are per node or per cell, and where the rows
# come from: a series is written in rows of a partition (older files) or of
# global ids; both are put in global id order before comparing.
NODE_PREFIXES = ("/mesh/coordinates", "/static/node/", "/fields/node/")
CELL_PREFIXES = ("/mesh/topology", "/static/cell/", "/fields/cell/")
# The owner rank of each cell depends on the partition, not a result (the
# per-step owner_rank exists only in runs that repartition).
# The hexes' rows (/static/hex/, /fields/hex/) are in global hex order already.
PARTITION = (
    "/static/cell/rank",
    "/fields/cell/owner_rank",
    "/static/hex/rank",
    "/fields/hex/owner_rank",
)


def itemsize(h5, ds):
    out = subprocess.run(["h5dump", "-H", "-d", ds, h5], check=True, capture_output=True, text=True).stdout
    if "H5T_STD_I32" in out or "H5T_STD_U32" in out:
        return 4
    if "H5T_STD_U8" in out or "H5T_STD_I8" in out:
        return 1
    return 8


class Order:
    """Row permutations that put a series' node and cell rows in global id order."""

    def __init__(self, h5, tmp):
        self.node = self.cell = None
        if "/static/node/node_id" not in datasets(h5):
            return
        ids = array.array("i", raw(h5, "/static/node/node_id", tmp))
        self.node = sorted(range(len(ids)), key=lambda r: ids[r])
        topo = array.array("I", raw(h5, "/mesh/topology", tmp))
        keys = [tuple(ids[topo[4 * c + k]] for k in range(4)) for c in range(len(topo) // 4)]
        self.cell = sorted(range(len(keys)), key=lambda c: keys[c])
        self.ids = ids

    def rows(self, ds, data, size):
        """`data` (raw bytes) with its rows in global id order."""
        perm = None
        if self.node is not None and ds.startswith(NODE_PREFIXES):
            perm = self.node
        elif self.cell is not None and ds.startswith(CELL_PREFIXES):
            perm = self.cell
        if perm is None or not perm:
            return data
        width = len(data) // len(perm)
        out = b"".join(data[r * width:(r + 1) * width] for r in perm)
        if ds == "/mesh/topology":
            t = array.array("I", out)
            out = array.array("I", (self.ids[v] for v in t)).tobytes()
        if ds == "/static/node/node_id":
            out = array.array("i", sorted(array.array("i", out))).tobytes()
        return out


def compare_file(a, case, label, ra, na, oa, ob, tmp):
    """Compares one HDF5 file of the reference and the new run (rows put in
    global id order by `oa` and `ob`); returns (differences, exact, worst)."""
    bad, exact, worst = 0, 0, 0.0
    dr = [d for d in datasets(ra) if d not in PARTITION]
    dn = [d for d in datasets(na) if d not in PARTITION]
    if dr != dn:
        print("%s/%s: datasets differ: %s" % (case, label, sorted(set(dr) ^ set(dn))))
        return 1, 0, 0.0
    for ds in dr:
        x, y = raw(ra, ds, tmp), raw(na, ds, tmp)
        x, y = oa.rows(ds, x, 0), ob.rows(ds, y, 0)
        if any(t in ds for t in SUMMED) and len(x) == len(y) and len(x) % 8 == 0:
            su, sv = sum(array.array("d", x)), sum(array.array("d", y))
            if abs(su - sv) > a.rtol * max(abs(su), 1e-300):
                print("%s/%s %s: sums %.17g and %.17g differ" % (case, label, ds, su, sv))
                bad += 1
            else:
                exact += 1
        elif (any(t in ds for t in TOLERANT) or case in a.tolerant_case) and len(x) == len(
            y
        ) and len(x) % 8 == 0 and itemsize(na, ds) == 8:
            u, v = array.array("d", x), array.array("d", y)
            scale = max([abs(t) for t in u] + [1e-300])
            diff = max([abs(p - q) for p, q in zip(u, v)] + [0.0]) / scale
            worst = max(worst, diff)
            rtol = a.rtol if any(t in ds for t in TOLERANT) else a.case_rtol
            if diff > rtol:
                print("%s/%s %s: relative difference %.3e > %.1e" % (case, label, ds, diff, rtol))
                bad += 1
        elif x != y:
            print("%s/%s %s: not bitwise equal" % (case, label, ds))
            bad += 1
        else:
            exact += 1
    return bad, exact, worst


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("ref")
    ap.add_argument("new")
    ap.add_argument("--rtol", type=float, default=1e-10)
    ap.add_argument(
        "--tolerant-case",
        action="append",
        default=[],
        help="a case whose motion follows its temperatures (thermal expansion): every "
        "floating-point dataset compared to --case-rtol, not bitwise (repeatable)",
    )
    ap.add_argument("--case-rtol", type=float, default=1e-8)
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
                oa, ob = Order(ra, tmp), Order(na, tmp)
                # The file itself, then a series' step files in its row order.
                files = [(name, ra, na)]
                steps = name[: -len(".h5")] + "_steps"
                rs, ns = os.path.join(rd, steps), os.path.join(nd, steps)
                if os.path.isdir(rs):
                    fr = sorted(f for f in os.listdir(rs) if f.endswith(".h5"))
                    fn = sorted(f for f in os.listdir(ns) if f.endswith(".h5")) if os.path.isdir(ns) else []
                    if fr != fn:
                        print("%s/%s: step files differ: %s" % (case, steps, sorted(set(fr) ^ set(fn))[:6]))
                        bad += 1
                        continue
                    files += [(steps + "/" + f, os.path.join(rs, f), os.path.join(ns, f)) for f in fr]
                for label, x, y in files:
                    b, e, w = compare_file(a, case, label, x, y, oa, ob, tmp)
                    bad, exact, worst = bad + b, exact + e, max(worst, w)
            print("%-24s %4d datasets bitwise, temperatures within %.2e" % (case, exact, worst))
    if bad:
        print("compare-outputs: %d difference(s)" % bad)
        return 1
    print("compare-outputs: same")
    return 0


if __name__ == "__main__":
    sys.exit(main())
