//! The half bonds that carry heat between a sphere lattice and the finite
//! elements (issue 21, seed 002): the mechanical links of
//! [`super::particle_region`] with conductance weights that put the heat
//! where a uniform flux puts it on the interface, plus the outward edge
//! half bonds of the spheres on the lateral surfaces of the lattice.
//!
//! Not in the seeds: the weights, derived here. In a uniform gradient G
//! across the interface (T = G x, x normal to it) every link, the sphere's
//! half bond to the element's point at the bond midpoint (conductance 2 h
//! w, `thermal::lattice_heat`), carries 2 h w G r: the heat each link gives
//! the face is proportional to its weight and lands at its midpoint. The
//! face links' midpoints are the centres of the spheres' 2r squares on the
//! face (the midpoint rule of the uniform flux); the edge links' midpoints
//! are the lines between the squares, each interior line taking two half
//! bonds of weight 2 (one from each side): the trapezoid rule of the flux.
//! Both integrate the linear shape functions of the face exactly, so the
//! nodes get the heat a uniform flux gives them. A sphere on a lateral
//! surface of the lattice has no neighbour beyond it, so the lattice
//! weight of its inward edge bond is (f_s + f_g)/2 with f_s = 2
//! (`mesh::lattice`): its link has weight 2 + f_g, and the line at the
//! face's edge gets nothing while the first interior line gets 3 + 3 = 6
//! instead of 4; the nodes at the edge of the face then lack heat
//! (docs/validation.md: 3.6 % of ΔT at the corners of the face). At the
//! interface the sphere's outward edge half bond exists, though: it runs
//! from the sphere to the face's edge, inside the sphere's own cell, and
//! the element holds its other end. Two conditions fix the split of the
//! weight 2 + f_g between the inward link (w_in) and the outward one
//! (w_out): the sphere's heat balance in the uniform gradient (its links
//! carry what its lattice bonds carry: w_in + w_out = 2 + f_g) and the
//! trapezoid rule at the face's edge (the edge line takes half an interior
//! line: w_out = 2). Hence w_out = 2, w_in = f_g: the sphere's surface
//! share moves from the inward to the outward half bond. The mechanical
//! links keep the lattice weights: a bond's force has a lateral component
//! that the outward half bond would not balance (docs/validation.md).

use super::lattice::BondKind;

/// A sphere's half bond to the finite elements, for heat.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatLink {
    /// The sphere.
    pub sphere: u32,
    /// The element (of the remaining FE mesh) at the half bond's far end.
    pub point_elem: u32,
    /// N_I of `point_elem` at that end.
    pub point_shape: [f64; 4],
    /// Neighbour group.
    pub kind: BondKind,
    /// Weight of the half bond's conductance 2 h w (2 for an interior link).
    pub weight: f64,
}

/// What a cell next to a sphere holds, for [`outward_edge`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Beside {
    /// Nothing: outside the body.
    Empty,
    /// A sphere of the lattice.
    Sphere,
    /// A finite element one cell from a sphere (a ghost's cell).
    Ghost,
    /// Any other finite-element cell.
    Fe,
}

/// For an edge link of lattice offset `o` (two non-zero components, from
/// the sphere to the ghost), the outward edge half bond of the same sphere
/// (module docs), if the sphere is on a lateral surface there: the offset
/// o* that reverses the lateral component q of o, where the sphere's cell
/// has no neighbour at −o nor along −o_q (the lateral surface), the cell
/// along o_p, across the interface, is a ghost's, and o* itself leads out
/// of the body. Returns (o*, p). `beside(d)` says what the cell at offset
/// d from the sphere holds.
pub fn outward_edge(o: [i64; 3], beside: impl Fn([i64; 3]) -> Beside) -> Option<([i64; 3], usize)> {
    let axes: Vec<usize> = (0..3).filter(|&a| o[a] != 0).collect();
    if axes.len() != 2 || beside(o.map(|c| -c)) != Beside::Empty {
        return None;
    }
    for (q, p) in [(axes[0], axes[1]), (axes[1], axes[0])] {
        let mut star = o;
        star[q] = -o[q];
        let mut lateral = [0; 3];
        lateral[q] = -o[q];
        let mut across = [0; 3];
        across[p] = o[p];
        if beside(lateral) == Beside::Empty
            && beside(across) == Beside::Ghost
            && beside(star) == Beside::Empty
        {
            return Some((star, p));
        }
    }
    None
}

/// Conductance weights (inward link, outward half bond) of an edge link
/// whose lattice weight is `weight` = (2 + f_g)/2 (module docs: w_in =
/// f_g, w_out = 2).
pub fn split_weights(weight: f64) -> (f64, f64) {
    // Not in the seeds (module docs): heat balance w_in + w_out = 2w, trapezoid w_out = 2.
    (2.0 * weight - 2.0, 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bar along x whose lattice starts at x = 0 with the FE region
    /// below it, rows y ≥ 0 and z ≥ 0: the cells beside sphere (0, j, k).
    fn bar(j: i64, k: i64) -> impl Fn([i64; 3]) -> Beside {
        move |d: [i64; 3]| {
            let c = [d[0], j + d[1], k + d[2]];
            if c[1] < 0 || c[2] < 0 || c[1] > 3 || c[2] > 3 {
                Beside::Empty
            } else if c[0] == -1 {
                Beside::Ghost
            } else if c[0] < -1 {
                Beside::Fe
            } else {
                Beside::Sphere
            }
        }
    }

    #[test]
    fn only_lateral_surface_spheres_get_an_outward_half_bond() {
        // Row 0 on the face y = 0: the link (−1, 1, 0) has its outward twin (−1, −1, 0).
        assert_eq!(outward_edge([-1, 1, 0], bar(0, 2)), Some(([-1, -1, 0], 0)));
        // The link (−1, 0, 1) of the same sphere has both neighbours along z: none.
        assert_eq!(outward_edge([-1, 0, 1], bar(0, 2)), None);
        // At the bar's edge both families get one.
        assert_eq!(outward_edge([-1, 0, 1], bar(0, 0)), Some(([-1, 0, -1], 0)));
        // An inner row has its neighbour at −o.
        assert_eq!(outward_edge([-1, 1, 0], bar(1, 2)), None);
        // Row 3 on the face y = 3: the link (−1, −1, 0).
        assert_eq!(outward_edge([-1, -1, 0], bar(3, 1)), Some(([-1, 1, 0], 0)));
        // A face link is not an edge link.
        assert_eq!(outward_edge([-1, 0, 0], bar(0, 0)), None);
    }

    #[test]
    fn split_keeps_the_spheres_heat_and_gives_the_edge_line_half_an_inner_one() {
        // Lattice weight 1.5 (f_s = 2, f_g = 1): half bond 3 becomes 1 + 2.
        let (inward, outward) = split_weights(1.5);
        assert_eq!((inward, outward), (1.0, 2.0));
        assert_eq!(inward + outward, 2.0 * 1.5);
        // The first inner line: this sphere's inward 1 and the next row's 3 (f_s = 1, f_g = 2)
        // make 4, an interior line's 2 + 2; the edge line gets 2, half of it.
        assert_eq!(inward + 3.0, 4.0);
        // A lattice two rows thick (f_g = 2): 2 + 2 on both sides, 2 + 2 on the middle line.
        assert_eq!(split_weights(2.0), (2.0, 2.0));
    }
}
