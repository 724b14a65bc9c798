//! Exact contact surfaces (issue 15, item 3): two boxes, each a Tet4 mesh,
//! at arbitrary rotations and offsets, deep and shallow overlaps, and with
//! faces lying in the other mesh's interior grid planes or side by side with
//! its boundary. The run's total S = Σ (S_tar + S_con)/2 (seed 000 eq 25)
//! must equal, to 1e-10 relative on 1 and 2 ranks, the area computed here
//! without any mesh: each box's face rectangles clipped by the other box's
//! six half-spaces, halved.

use std::path::Path;

use crate::common::*;
use fdem::geometry::transform::rotation_xyz_degrees;

type P = [f64; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: P, b: P) -> P {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A box `origin + size` rotated about the global origin by `rotate`
/// (degrees about x, y, z, as a scenario's `rotate`), then translated.
struct Box3 {
    origin: P,
    size: P,
    rotate: P,
    translate: P,
    h: f64,
}

impl Box3 {
    fn map(&self, local: P) -> P {
        let r = rotation_xyz_degrees(self.rotate);
        let p = [
            self.origin[0] + local[0],
            self.origin[1] + local[1],
            self.origin[2] + local[2],
        ];
        let q = r * nalgebra::Vector3::new(p[0], p[1], p[2]);
        [
            q.x + self.translate[0],
            q.y + self.translate[1],
            q.z + self.translate[2],
        ]
    }

    /// The six faces as (corners in order, outward unit normal).
    fn faces(&self) -> Vec<(Vec<P>, P)> {
        let s = self.size;
        let c = |i: usize, j: usize, k: usize| {
            self.map([i as f64 * s[0], j as f64 * s[1], k as f64 * s[2]])
        };
        let quads = [
            [c(0, 0, 0), c(0, 0, 1), c(0, 1, 1), c(0, 1, 0)],
            [c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)],
            [c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)],
            [c(0, 1, 0), c(0, 1, 1), c(1, 1, 1), c(1, 1, 0)],
            [c(0, 0, 0), c(0, 1, 0), c(1, 1, 0), c(1, 0, 0)],
            [c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)],
        ];
        let mid = self.map([0.5 * s[0], 0.5 * s[1], 0.5 * s[2]]);
        quads
            .iter()
            .map(|q| {
                let mut n = cross(sub(q[1], q[0]), sub(q[2], q[0]));
                if dot(n, sub(q[0], mid)) < 0.0 {
                    n = n.map(|x| -x);
                }
                let l = dot(n, n).sqrt();
                (q.to_vec(), n.map(|x| x / l))
            })
            .collect()
    }

    fn toml(&self, name: &str) -> String {
        format!(
            "[[bodies]]\nname = \"{name}\"\nmaterial = \"m\"\n\
             mesh = {{ kind = \"box\", origin = {:?}, size = {:?}, element_size = {} }}\n\
             rotate = {:?}\ntranslate = {:?}\n",
            self.origin, self.size, self.h, self.rotate, self.translate
        )
    }
}

fn area(p: &[P]) -> f64 {
    if p.len() < 3 {
        return 0.0;
    }
    let mut s = [0.0; 3];
    for i in 1..p.len() - 1 {
        let c = cross(sub(p[i], p[0]), sub(p[i + 1], p[0]));
        s = [s[0] + c[0], s[1] + c[1], s[2] + c[2]];
    }
    0.5 * dot(s, s).sqrt()
}

/// Area of `x`'s boundary inside the closed box `y`: each face polygon
/// clipped by y's half-spaces. A face lying in one of y's face planes
/// counts when the two face each other (touching) and not when they lie
/// side by side (same outward normal).
fn boundary_inside(x: &Box3, y: &Box3) -> f64 {
    let tol = 1e-12;
    let planes: Vec<(P, f64)> = y
        .faces()
        .into_iter()
        .map(|(q, n)| (n, dot(n, q[0])))
        .collect();
    let mut total = 0.0;
    for (quad, nf) in x.faces() {
        let mut poly = quad;
        for &(n, c) in &planes {
            let d: Vec<f64> = poly.iter().map(|p| dot(n, *p) - c).collect();
            if d.iter().all(|v| v.abs() <= tol) {
                if dot(n, nf) > 0.0 {
                    poly.clear();
                }
                continue;
            }
            let mut next = Vec::new();
            for i in 0..poly.len() {
                let j = (i + 1) % poly.len();
                if d[i] <= tol {
                    next.push(poly[i]);
                }
                if (d[i] < -tol && d[j] > tol) || (d[i] > tol && d[j] < -tol) {
                    let s = d[i] / (d[i] - d[j]);
                    let (a, b) = (poly[i], poly[j]);
                    next.push([
                        a[0] + s * (b[0] - a[0]),
                        a[1] + s * (b[1] - a[1]),
                        a[2] + s * (b[2] - a[2]),
                    ]);
                }
            }
            poly = next;
            if poly.is_empty() {
                break;
            }
        }
        total += area(&poly);
    }
    total
}

/// Total contact area of a run: the sum of the per-body-pair areas it writes.
fn run_area(ranks: usize, dir: &Path, scenario: &Path) -> f64 {
    run_ok(ranks, scenario, dir, &[]);
    let text = std::fs::read_to_string(dir.join("boxes_body_contacts.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').nth(5).unwrap().parse::<f64>().unwrap())
        .sum()
}

fn check(tag: &str, a: Box3, b: Box3) {
    let exact = 0.5 * (boundary_inside(&a, &b) + boundary_inside(&b, &a));
    let dir = out_dir(&format!("surface/{tag}"));
    let scenario = dir.join("boxes.toml");
    let text = format!(
        "title = \"{tag}\"\n[time]\ndt = 1.0\nsteps = 1\n\
         [[materials]]\nname = \"m\"\nconductivity = 1.0\nspecific_heat = 1.0\ndensity = 1.0\n\
         {}{}[thermal]\ntheta = 1.0\n[contact]\nresistance = 0.01\n",
        a.toml("a"),
        b.toml("b")
    );
    std::fs::write(&scenario, text).unwrap();
    for ranks in [1, 2] {
        let run = dir.join(format!("np{ranks}"));
        let s = run_area(ranks, &run, &scenario);
        let rel = (s - exact).abs() / exact;
        println!("{tag}, {ranks} rank(s): S = {s:.12e}, exact {exact:.12e}, relative {rel:.2e}");
        assert!(
            rel < 1e-10,
            "{tag} on {ranks} rank(s): S = {s:e}, exact {exact:e} (relative {rel:e})"
        );
    }
}

fn unit_box(h: f64) -> Box3 {
    Box3 {
        origin: [0.0; 3],
        size: [1.0; 3],
        rotate: [0.0; 3],
        translate: [0.0; 3],
        h,
    }
}

fn small_box(translate: P, rotate: P) -> Box3 {
    Box3 {
        origin: [0.0; 3],
        size: [0.6, 0.5, 0.4],
        rotate,
        translate,
        h: 0.1,
    }
}

#[test]
fn side_faces_in_the_other_meshs_grid_planes_count_once() {
    // The case: the small box's y and z faces lie in the unit box's
    // interior grid planes (h = 0.1) over its 1 mm penetration: S = 0.2009.
    let exact = 0.5 * (0.2 + 0.2 + 2.0 * 0.001 * 0.4 + 2.0 * 0.001 * 0.5);
    let a = unit_box(0.1);
    let b = small_box([0.999, 0.2, 0.3], [0.0; 3]);
    let reference = 0.5 * (boundary_inside(&a, &b) + boundary_inside(&b, &a));
    assert!((reference - exact).abs() < 1e-14, "{reference}");
    check("grid-planes", a, b);
    // The same away from the grid planes.
    check(
        "off-grid",
        unit_box(0.1),
        small_box([0.999, 0.23, 0.31], [0.0; 3]),
    );
}

#[test]
fn box_inside_a_box_on_its_grid_planes() {
    // Every face of the small box lies in a grid plane of the unit box.
    check(
        "inside-on-grid",
        unit_box(0.1),
        small_box([0.3, 0.2, 0.3], [0.0; 3]),
    );
}

#[test]
fn coplanar_flanks_side_by_side_do_not_count() {
    // The small box's y = 0 and z = 0 faces lie on the unit box's own
    // boundary faces, side by side: only its x = 0.5 face (and the unit
    // box's x = 1 face) make contact area.
    check(
        "flanks",
        unit_box(0.1),
        small_box([0.5, 0.0, 0.0], [0.0; 3]),
    );
}

#[test]
fn rotated_boxes_deep_and_shallow() {
    check(
        "rotated-deep",
        unit_box(0.125),
        small_box([0.7, 0.55, 0.6], [17.0, -31.0, 43.0]),
    );
    check(
        "rotated-shallow",
        unit_box(0.125),
        small_box([0.97, 0.2, 0.25], [3.0, 5.0, -7.0]),
    );
    // Both rotated, an edge of one cutting into a face of the other.
    let mut a = unit_box(0.125);
    a.rotate = [0.0, 0.0, 12.0];
    check(
        "both-rotated",
        a,
        small_box([0.6, 0.6, 0.9], [45.0, 35.0, 0.0]),
    );
}
