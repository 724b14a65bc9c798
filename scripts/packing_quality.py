#!/usr/bin/env python3
"""Packing quality of a deposited nut packing, read from its checkpoint.

Prints the two figures docs/validation.md gives for the deposition stage:
- the deepest particle node below the container's floor top (how far the
  softened penalty lets corners sink);
- the apparent solid fraction: the particles' volume whose centroid lies
  below the 90th-percentile centroid height, over the container's inner
  cross-section times that height above the floor.

Usage: /usr/bin/python3 scripts/packing_quality.py CHECKPOINT.h5 [--radius R] [--container NAME]
(h5py and numpy: Debian's python3-h5py, installed by scripts/setup.sh --bench).
"""
import argparse

import h5py
import numpy as np


def tet_volumes(p):
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    return np.abs(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("checkpoint")
    ap.add_argument("--radius", type=float, default=0.225, help="container inner radius (m)")
    ap.add_argument("--container", default="container", help="the container body's name")
    args = ap.parse_args()
    with h5py.File(args.checkpoint, "r") as f:
        x = f["state/positions"][:]
        tets = f["mesh/tets"][:]
        body = f["mesh/body"][:]
        names = f["bodies/names"][:].tobytes().decode().split("\n")
    if args.container not in names:
        raise SystemExit(f"{args.checkpoint}: no body named {args.container!r}")
    c = names.index(args.container)
    wall_nodes = np.unique(tets[body == c].ravel())
    wx = x[wall_nodes]
    inside = np.hypot(wx[:, 0], wx[:, 1]) < args.radius - 1e-9
    if not inside.any():
        raise SystemExit(f"{args.checkpoint}: the container has no node inside r = {args.radius}")
    floor = wx[inside][:, 2].max()
    particles = body != c
    deepest = floor - x[np.unique(tets[particles].ravel())][:, 2].min()
    centroids, volumes = [], []
    for b in np.unique(body[particles]):
        p = x[tets[body == b]]
        v = tet_volumes(p)
        centroids.append((p.mean(axis=1) * v[:, None]).sum(axis=0) / v.sum())
        volumes.append(v.sum())
    z = np.array(centroids)[:, 2]
    volumes = np.array(volumes)
    h90 = np.percentile(z, 90) - floor
    fraction = volumes[z - floor <= h90].sum() / (np.pi * args.radius**2 * h90)
    print(
        f"{len(volumes)} particles; deepest node {deepest * 1e3:.1f} mm below the floor top; "
        f"90th-percentile centroid height {h90:.4f} m; apparent solid fraction {fraction:.3f}"
    )


if __name__ == "__main__":
    main()
