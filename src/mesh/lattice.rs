//! Bonded cubic lattice of spheres (seed 002 Fig 2): spheres of radius r
//! at the centres of the cubes of side 2r that fill a box, each bonded to
//! its (up to) 26 neighbours, grouped by distance as in Fig 2b: face
//! neighbours at 2r (group 1), edge neighbours at 2√2 r (group 2) and
//! corner neighbours at 2√3 r (group 3). Each bond is stored once.
//!
//! Boundary weights. Eq 4 of seed 002 is an energy equivalence per cell: a
//! sphere owns half of each of its bonds, and with both bonds of a
//! direction pair ±n present its cell stores the continuum energy of a
//! uniform strain exactly. A sphere on a free surface lacks the bonds that
//! would leave the body, so its cell is softer (by 17 % along the surface
//! for ν = 0.23), and a beam of 8 spheres through the thickness bends 18 %
//! more than the continuum (measured, `docs/validation.md`). The generator
//! therefore gives each bond the weight w = (f_i + f_j)/2, with f = 2/c
//! and c ∈ {1, 2} the number of neighbours the sphere has along ±n: each
//! cell then keeps the interior energy of each direction pair that has at
//! least one bond. Only spheres on the 12 edges of the box miss a diagonal
//! pair entirely (both neighbours outside), so the lattice stores the
//! energy of the continuum box under a uniform strain up to those edge
//! cells. Interior bonds keep w = 1, i.e. exactly eq 4.

use super::MeshError;

/// Neighbour group of a bond (seed 002 Fig 2b).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BondKind {
    /// Group 1: the 6 face neighbours, distance 2r.
    Face = 0,
    /// Group 2: the 12 edge neighbours, distance 2√2 r.
    Edge = 1,
    /// Group 3: the 8 corner neighbours, distance 2√3 r.
    Corner = 2,
}

/// One bond between spheres `i` < `j`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeBond {
    /// First sphere.
    pub i: u32,
    /// Second sphere.
    pub j: u32,
    /// Neighbour group.
    pub kind: BondKind,
    /// Boundary weight multiplying the bond's stiffness and conductance:
    /// 1 inside, 1.5 or 2 for bonds of surface spheres (module docs).
    pub weight: f64,
}

/// A cubic lattice of spheres.
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    /// Sphere radius r (m); the lattice spacing is 2r.
    pub radius: f64,
    /// Spheres per axis.
    pub counts: [usize; 3],
    /// Sphere centres (m); on a whole box, sphere (i, j, k) has index
    /// i + n0 (j + n1 k).
    pub centres: Vec<[f64; 3]>,
    /// Per cell i + n0 (j + n1 k) of the box, its sphere, or `u32::MAX`
    /// where [`cubic_lattice_where`] left the cell empty.
    pub grid: Vec<u32>,
    /// Bonds, each once.
    pub bonds: Vec<LatticeBond>,
}

impl Lattice {
    /// Index of sphere (i, j, k) (`u32::MAX` as usize for an empty cell).
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        self.grid[i + self.counts[0] * (j + self.counts[1] * k)] as usize
    }

    /// Volume of the cube of side 2r each sphere stands for (m³).
    pub fn cell_volume(&self) -> f64 {
        (2.0 * self.radius).powi(3)
    }
}

/// The lattice filling the box [lo, hi] with spheres of radius `radius`:
/// each side must be a whole number of diameters (to 1e-9 relative).
/// `corners` keeps the group-3 bonds (seed 002 eq 4 gives them no
/// stiffness, so a mechanics-only model may leave them out).
pub fn cubic_lattice(
    lo: [f64; 3],
    hi: [f64; 3],
    radius: f64,
    corners: bool,
) -> Result<Lattice, MeshError> {
    cubic_lattice_where(lo, hi, radius, corners, |_| true)
}

/// The spheres of [`cubic_lattice`]`(lo, hi, radius, corners)` whose
/// centres `keep` accepts, numbered in the box's cell order, each bonded to
/// its kept neighbours; a bond's boundary weight counts a missing
/// neighbour as outside the body (module docs).
pub fn cubic_lattice_where(
    lo: [f64; 3],
    hi: [f64; 3],
    radius: f64,
    corners: bool,
    keep: impl Fn([f64; 3]) -> bool,
) -> Result<Lattice, MeshError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(MeshError::InvalidParameter(format!(
            "lattice radius must be positive, got {radius}"
        )));
    }
    let mut counts = [0usize; 3];
    for a in 0..3 {
        let len = hi[a] - lo[a];
        let n = (len / (2.0 * radius)).round();
        if !(len > 0.0 && n >= 1.0 && (n * 2.0 * radius - len).abs() <= 1e-9 * len) {
            return Err(MeshError::InvalidParameter(format!(
                "lattice box side {a} of length {len} m is not a whole number of diameters 2r = {} m",
                2.0 * radius
            )));
        }
        counts[a] = n as usize;
    }
    super::check_element_count(
        "the sphere lattice",
        counts.iter().map(|&c| c as u128).product(),
    )?;
    let mut centres = Vec::with_capacity(counts[0] * counts[1] * counts[2]);
    let mut grid = Vec::with_capacity(counts[0] * counts[1] * counts[2]);
    for k in 0..counts[2] {
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let c = [i, j, k];
                let x = std::array::from_fn(|a| lo[a] + radius * (2 * c[a] + 1) as f64);
                if keep(x) {
                    grid.push(centres.len() as u32);
                    centres.push(x);
                } else {
                    grid.push(u32::MAX);
                }
            }
        }
    }
    // The 13 offsets with the first non-zero component positive: each bond once.
    let mut offsets = Vec::new();
    for dk in -1i64..=1 {
        for dj in -1i64..=1 {
            for di in -1i64..=1 {
                let o = [di, dj, dk];
                let first = o.iter().rev().find(|&&c| c != 0);
                if first.is_some_and(|&c| c > 0) {
                    offsets.push(o);
                }
            }
        }
    }
    let mut bonds = Vec::new();
    let n = counts.map(|c| c as i64);
    // The sphere of cell c, if the cell is in the box and kept.
    let sphere = |c: [i64; 3]| {
        ((0..3).all(|a| c[a] >= 0 && c[a] < n[a]))
            .then(|| grid[(c[0] + n[0] * (c[1] + n[1] * c[2])) as usize])
            .filter(|&g| g != u32::MAX)
    };
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let Some(a) = sphere([i, j, k]) else {
                    continue;
                };
                for o in &offsets {
                    let (p, q, r) = (i + o[0], j + o[1], k + o[2]);
                    let Some(b) = sphere([p, q, r]) else {
                        continue;
                    };
                    let kind = match o.iter().map(|c| c * c).sum::<i64>() {
                        1 => BondKind::Face,
                        2 => BondKind::Edge,
                        _ => BondKind::Corner,
                    };
                    if kind == BondKind::Corner && !corners {
                        continue;
                    }
                    // Neighbours along ±o of a sphere: the bond itself plus the opposite one if present.
                    let share = |c: [i64; 3], sign: i64| {
                        let back = [c[0] + sign * o[0], c[1] + sign * o[1], c[2] + sign * o[2]];
                        if sphere(back).is_some() {
                            1.0
                        } else {
                            2.0
                        }
                    };
                    let weight = 0.5 * (share([i, j, k], -1) + share([p, q, r], 1));
                    bonds.push(LatticeBond {
                        i: a.min(b),
                        j: a.max(b),
                        kind,
                        weight,
                    });
                }
            }
        }
    }
    Ok(Lattice {
        radius,
        counts,
        centres,
        grid,
        bonds,
    })
}

/// "This part of the body is particles" (issue 21): the lattice of spheres
/// of radius `radius` whose centres lie in the elements of set `set` of
/// `mesh`, on the grid of diameters from the set's lowest corner (its box
/// rounded up to whole diameters). An error names a missing set (with the
/// sets there are) or a set too thin for one sphere.
pub fn lattice_in_element_set(
    mesh: &super::TetMesh,
    set: &str,
    radius: f64,
    corners: bool,
) -> Result<Lattice, MeshError> {
    let elements = mesh.elem_sets.get(set).ok_or_else(|| {
        let known: Vec<&str> = mesh.elem_sets.keys().map(String::as_str).collect();
        MeshError::InvalidParameter(format!(
            "no element set `{set}` for the lattice (sets: {})",
            known.join(", ")
        ))
    })?;
    let corners_of = |e: u32| mesh.tets[e as usize].map(|v| mesh.nodes[v as usize]);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &e in elements {
        for x in corners_of(e) {
            for a in 0..3 {
                lo[a] = lo[a].min(x[a]);
                hi[a] = hi[a].max(x[a]);
            }
        }
    }
    let d = 2.0 * radius;
    if !(radius.is_finite() && radius > 0.0) || elements.is_empty() {
        return Err(MeshError::InvalidParameter(format!(
            "lattice in element set `{set}`: radius {radius} m on {} elements",
            elements.len()
        )));
    }
    let hi: [f64; 3] = std::array::from_fn(|a| lo[a] + d * ((hi[a] - lo[a]) / d).ceil().max(1.0));
    // Each element marks the cells whose centres it holds (its box's cells only).
    let n: [usize; 3] = std::array::from_fn(|a| ((hi[a] - lo[a]) / d).round() as usize);
    let mut held = vec![false; n[0] * n[1] * n[2]];
    for &e in elements {
        let t = corners_of(e);
        let planes = crate::geometry::TetPlanes::new(&t);
        let range = |a: usize| {
            let (mut l, mut h) = (f64::INFINITY, f64::NEG_INFINITY);
            for x in &t {
                l = l.min(x[a]);
                h = h.max(x[a]);
            }
            let first = (((l - lo[a]) / d - 0.5).ceil().max(0.0)) as usize;
            let last = (((h - lo[a]) / d - 0.5).floor() as i64).min(n[a] as i64 - 1);
            (first, last)
        };
        let (rx, ry, rz) = (range(0), range(1), range(2));
        for k in rz.0 as i64..=rz.1 {
            for j in ry.0 as i64..=ry.1 {
                for i in rx.0 as i64..=rx.1 {
                    let c = [i, j, k].map(|v| v as usize);
                    let x = std::array::from_fn(|a| lo[a] + radius * (2 * c[a] + 1) as f64);
                    // A centre on a face shared by two elements counts once either way.
                    if planes.contains(x, 1e-12 * d) {
                        held[c[0] + n[0] * (c[1] + n[1] * c[2])] = true;
                    }
                }
            }
        }
    }
    let cell = |x: [f64; 3]| -> usize {
        let c: [usize; 3] = std::array::from_fn(|a| ((x[a] - lo[a]) / d - 0.5).round() as usize);
        c[0] + n[0] * (c[1] + n[1] * c[2])
    };
    let lattice = cubic_lattice_where(lo, hi, radius, corners, |x| held[cell(x)])?;
    if lattice.centres.is_empty() {
        return Err(MeshError::InvalidParameter(format!(
            "lattice in element set `{set}`: no sphere of radius {radius} m has its centre in the set"
        )));
    }
    Ok(lattice)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interior_sphere_has_26_neighbours_grouped_6_12_8() {
        let l = cubic_lattice([0.0; 3], [1.0, 1.0, 1.0], 1.0 / 6.0, true).unwrap();
        assert_eq!(l.counts, [3, 3, 3]);
        let centre = l.index(1, 1, 1) as u32;
        let mut groups = [0usize; 3];
        for b in &l.bonds {
            assert!(b.i < b.j);
            if b.i == centre || b.j == centre {
                groups[b.kind as usize] += 1;
                let (p, q) = (l.centres[b.i as usize], l.centres[b.j as usize]);
                let d = ((0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>()).sqrt();
                let expect = 2.0 * l.radius * [1.0, 2f64.sqrt(), 3f64.sqrt()][b.kind as usize];
                assert!((d - expect).abs() < 1e-12);
            }
        }
        assert_eq!(groups, [6, 12, 8]);
        // 27 spheres: 54 face, 72 edge and 32 corner bonds, each once.
        assert_eq!(l.bonds.len(), 54 + 72 + 32);
        let no_corners = cubic_lattice([0.0; 3], [1.0; 3], 1.0 / 6.0, false).unwrap();
        assert_eq!(no_corners.bonds.len(), 54 + 72);
        assert!(cubic_lattice([0.0; 3], [1.0, 1.0, 0.9], 0.3, true).is_err());
        // Weights, on a 5×5×5 block: the bonds of the centre sphere join interior spheres
        // (1); the face bond from a corner sphere to its x neighbour has the corner's half
        // doubled: (2 + 1)/2.
        let l = cubic_lattice([0.0; 3], [1.0; 3], 0.1, true).unwrap();
        let centre = l.index(2, 2, 2) as u32;
        for b in &l.bonds {
            if b.i == centre || b.j == centre {
                assert_eq!(b.weight, 1.0);
            }
        }
        let corner = l.index(0, 0, 0) as u32;
        let next = l.index(1, 0, 0) as u32;
        let edge = l
            .bonds
            .iter()
            .find(|b| b.i == corner && b.j == next)
            .unwrap();
        assert_eq!(edge.weight, 1.5);
    }

    /// The lattice of an element set that is a box is that box's lattice;
    /// an L-shaped set keeps the spheres whose centres it holds, bonded to
    /// their kept neighbours with weights from the kept neighbours alone.
    #[test]
    fn a_lattice_fills_an_element_set() {
        let mut mesh = crate::mesh::generate::box_mesh([0.0; 3], [2.0, 1.0, 1.0], 0.25).unwrap();
        mesh.add_box_set("right", [1.0, 0.0, 0.0], [2.0, 1.0, 1.0])
            .unwrap();
        let got = lattice_in_element_set(&mesh, "right", 0.125, true).unwrap();
        let want = cubic_lattice([1.0, 0.0, 0.0], [2.0, 1.0, 1.0], 0.125, true).unwrap();
        assert_eq!(got.centres.len(), 4 * 4 * 4);
        for (a, b) in got.centres.iter().zip(&want.centres) {
            assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-12), "{a:?} {b:?}");
        }
        assert_eq!(got.bonds, want.bonds);

        // L: the bottom half in y over the whole length, and the top half over x < 1.
        let centroid = |e: usize| {
            let t = mesh.tets[e].map(|v| mesh.nodes[v as usize]);
            [0, 1, 2].map(|a| t.iter().map(|x| x[a]).sum::<f64>() / 4.0)
        };
        let l: Vec<u32> = (0..mesh.tets.len())
            .filter(|&e| {
                let c = centroid(e);
                c[1] < 0.5 || c[0] < 1.0
            })
            .map(|e| e as u32)
            .collect();
        mesh.elem_sets.insert("L".into(), l);
        let r = 0.125;
        let got = lattice_in_element_set(&mesh, "L", r, true).unwrap();
        // 8 × 2 × 4 spheres below y = 0.5 and 4 × 2 × 4 above it.
        assert_eq!(got.centres.len(), 64 + 32);
        let in_l = |x: [f64; 3]| {
            (0.0..2.0).contains(&x[0])
                && (0.0..1.0).contains(&x[1])
                && (0.0..1.0).contains(&x[2])
                && (x[1] < 0.5 || x[0] < 1.0)
        };
        assert!(got.centres.iter().all(|&x| in_l(x)));
        // Every pair at 2r, 2√2 r, 2√3 r is bonded once, with the weight
        // of its spheres' kept neighbours along the bond.
        let mut want = Vec::new();
        let d = 2.0 * r;
        for (i, a) in got.centres.iter().enumerate() {
            for (j, b) in got.centres.iter().enumerate().skip(i + 1) {
                let o = [0, 1, 2].map(|k| ((b[k] - a[k]) / d).round() as i64);
                let n2: i64 = o.iter().map(|c| c * c).sum();
                if o.iter().any(|c| c.abs() > 1) {
                    continue;
                }
                let kind = [BondKind::Face, BondKind::Edge, BondKind::Corner][n2 as usize - 1];
                let share = |x: &[f64; 3], sign: f64| {
                    let back = [0, 1, 2].map(|k| x[k] + sign * d * o[k] as f64);
                    if in_l(back) {
                        1.0
                    } else {
                        2.0
                    }
                };
                let weight = 0.5 * (share(a, -1.0) + share(b, 1.0));
                want.push((i as u32, j as u32, kind, weight));
            }
        }
        let mut have: Vec<_> = got
            .bonds
            .iter()
            .map(|b| (b.i, b.j, b.kind, b.weight))
            .collect();
        have.sort_by_key(|p| (p.0, p.1));
        want.sort_by_key(|p| (p.0, p.1));
        assert_eq!(have, want);
        // Cells outside the L have no sphere.
        assert_eq!(got.index(7, 3, 0), u32::MAX as usize);

        let e = lattice_in_element_set(&mesh, "left", r, true)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no element set `left`") && e.contains("right"),
            "{e}"
        );
        mesh.elem_sets.insert("one".into(), vec![0]);
        let e = lattice_in_element_set(&mesh, "one", 10.0, true)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no sphere"), "{e}");
    }
}
