//! Throughput of the exact tet–tet overlap kernel (issue 22: about 40 % of
//! a dense deposition's substep): `overlap_state` (the clipping of
//! `geometry::tet_tet_intersection_with` and the volume gradient) over the
//! tet pairs of two default nuts whose bounding boxes overlap, the second
//! nut turned and pressed into the first by a small depth, as the pairs of
//! a settled packing. Prints pairs/s on one core and a checksum of every
//! result (volume, gradient, centroid), so a change of the kernel that
//! should keep its results bitwise can be checked against the last run.
//! Run: cargo run --release --example overlap_kernel_bench [repetitions]

#[path = "common/timing.rs"]
mod timing;

use fdem::contact::penalty::overlap_state;
use fdem::geometry::{tet_bounds, TetPlanes};
use fdem::mesh::nut::nut_mesh_default;

type Tet = [[f64; 3]; 4];

fn tets_of(nodes: &[[f64; 3]], tets: &[[u32; 4]]) -> Vec<Tet> {
    tets.iter().map(|t| t.map(|n| nodes[n as usize])).collect()
}

fn main() {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20);
    let a = nut_mesh_default([0.0; 3]).expect("nut");
    let ta = tets_of(&a.nodes, &a.tets);
    let (lo, hi) = ta.iter().fold(([f64::MAX; 3], [f64::MIN; 3]), |(l, h), t| {
        let (tl, th) = tet_bounds(t);
        (
            std::array::from_fn(|d| l[d].min(tl[d])),
            std::array::from_fn(|d| h[d].max(th[d])),
        )
    });
    let size = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    // Pairs of several poses of the second nut: each turned about a tilted
    // axis and moved sideways so that its side sinks into the first nut
    // by 0.5–2 % of the nut's size.
    let mut pairs: Vec<(Tet, Tet)> = Vec::new();
    for k in 0..24 {
        let depth = [0.005, 0.01, 0.02][k % 3];
        let angle = 0.3 + 0.37 * k as f64;
        let (c, s) = (angle.cos(), angle.sin());
        let turn = |p: [f64; 3]| [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
        let turned: Vec<Tet> = ta.iter().map(|t| t.map(turn)).collect();
        let low_x = turned
            .iter()
            .flat_map(|t| t.iter().map(|p| p[0]))
            .fold(f64::MAX, f64::min);
        let shift = [
            hi[0] - depth * size - low_x,
            0.05 * size * (k % 5) as f64,
            0.03 * size * (k % 7) as f64,
        ];
        let b: Vec<Tet> = turned
            .iter()
            .map(|t| t.map(|p| [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]]))
            .collect();
        for x in &ta {
            let (xl, xh) = tet_bounds(x);
            for y in &b {
                let (yl, yh) = tet_bounds(y);
                if (0..3).all(|d| xl[d] <= yh[d] && yl[d] <= xh[d]) {
                    pairs.push((*x, *y));
                }
            }
        }
    }
    // The substep clips only pairs that no axis separates: the touching ones.
    let boxed = pairs.len();
    pairs
        .retain(|(x, y)| overlap_state((x, &TetPlanes::new(x)), (y, &TetPlanes::new(y))).is_some());
    let planes: Vec<(TetPlanes, TetPlanes)> = pairs
        .iter()
        .map(|(x, y)| (TetPlanes::new(x), TetPlanes::new(y)))
        .collect();
    let mut checksum = 0u64;
    let mut touching = 0usize;
    let (wall, cpu) = timing::time_best(reps, || {
        let (mut sum, mut n) = (0u64, 0usize);
        for ((x, y), (px, py)) in pairs.iter().zip(&planes) {
            if let Some(s) = overlap_state((x, px), (y, py)) {
                n += 1;
                let mut h = s.volume.to_bits();
                for g in s.grad.iter().flatten().chain(&s.point) {
                    h = h.rotate_left(7) ^ g.to_bits();
                }
                sum = sum.wrapping_add(h);
            }
        }
        checksum = sum;
        touching = n;
    });
    let t = cpu.unwrap_or(wall);
    println!(
        "overlap kernel: {} touching pairs (of {} box-overlapping), {:.3} M pairs/s, {:.0} ns/pair, checksum {:016x}",
        touching,
        boxed,
        pairs.len() as f64 / t / 1e6,
        t / pairs.len() as f64 * 1e9,
        checksum
    );
}
