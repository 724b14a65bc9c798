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
    /// Sphere centres (m); sphere (i, j, k) has index i + n0 (j + n1 k).
    pub centres: Vec<[f64; 3]>,
    /// Bonds, each once.
    pub bonds: Vec<LatticeBond>,
}

impl Lattice {
    /// Index of sphere (i, j, k).
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.counts[0] * (j + self.counts[1] * k)
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
    for k in 0..counts[2] {
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let c = [i, j, k];
                centres.push(std::array::from_fn(|a| {
                    lo[a] + radius * (2 * c[a] + 1) as f64
                }));
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
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let a = (i + n[0] * (j + n[1] * k)) as u32;
                for o in &offsets {
                    let (p, q, r) = (i + o[0], j + o[1], k + o[2]);
                    if p < 0 || q < 0 || r < 0 || p >= n[0] || q >= n[1] || r >= n[2] {
                        continue;
                    }
                    let kind = match o.iter().map(|c| c * c).sum::<i64>() {
                        1 => BondKind::Face,
                        2 => BondKind::Edge,
                        _ => BondKind::Corner,
                    };
                    if kind == BondKind::Corner && !corners {
                        continue;
                    }
                    let b = (p + n[0] * (q + n[1] * r)) as u32;
                    // Neighbours along ±o of a sphere: the bond itself plus the opposite one if present.
                    let inside = |c: [i64; 3]| (0..3).all(|a| c[a] >= 0 && c[a] < n[a]);
                    let share = |c: [i64; 3], sign: i64| {
                        let back = [c[0] + sign * o[0], c[1] + sign * o[1], c[2] + sign * o[2]];
                        if inside(back) {
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
        bonds,
    })
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
}
