//! "This part of the body is particles" (issue 21, seed 002): an element
//! set of a Tet4 body turned into a bonded sphere lattice joined to the
//! rest of the body, which stays finite elements, by the ghost layer of
//! seed 002 eq 5.
//!
//! The grid is that of [`super::lattice::lattice_in_element_set`] (cells of
//! side 2r from the set's lowest corner). Its cells are spheres (centre in
//! the set), ghosts (centre in a remaining element, one cell from a sphere:
//! the mirror images x_b − 2 r n of the boundary spheres along each bond
//! direction that leaves the set), and a second layer of FE cells that only
//! complete the boundary weights: each bond's weight counts the cells
//! beyond its ends as if the lattice went on through the FE region, so an
//! interface sphere is not a free-surface sphere. Sphere–sphere bonds stay
//! lattice bonds; each sphere–ghost bond becomes a link, the sphere's half
//! of the bond (twice the stiffness) attached to the element's material
//! point at the bond's midpoint on the interface, as the serial drivers'
//! default coupling does (`validation::fede_coupling`, module docs there).
//! Pure code: no MPI.

use super::heat_links::{outward_edge, split_weights, Beside, HeatLink};
use super::lattice::{cubic_lattice_where, BondKind, LatticeBond};
use super::{MeshError, TetMesh};
use crate::geometry::TetPlanes;
use crate::mechanics::ghost::tet4_ghost;
use nalgebra::Vector3;

/// A sphere's half bond to the finite elements.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionLink {
    /// The sphere (index into [`ParticleRegion::centres`]).
    pub sphere: u32,
    /// The element (of the remaining FE mesh) that holds the ghost.
    pub ghost_elem: u32,
    /// N_I of `ghost_elem` at the ghost (its position gives the bond's direction).
    pub ghost_shape: [f64; 4],
    /// The element (of the remaining FE mesh) at the bond's midpoint.
    pub point_elem: u32,
    /// N_I of `point_elem` at the midpoint.
    pub point_shape: [f64; 4],
    /// Neighbour group.
    pub kind: BondKind,
    /// Weight of the half bond (twice the lattice weight).
    pub weight: f64,
}

/// The particles of an element set and their links to the rest of the body.
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleRegion {
    /// Sphere radius (m).
    pub radius: f64,
    /// Sphere centres (m), in the grid's cell order.
    pub centres: Vec<[f64; 3]>,
    /// Per sphere, the element of the set its centre lies in (the given
    /// mesh's numbering; the lowest where it lies on a shared face).
    pub source_elem: Vec<u32>,
    /// Sphere–sphere bonds (indices into `centres`), each once.
    pub bonds: Vec<LatticeBond>,
    /// Sphere–FE half bonds, in the lattice's bond order.
    pub links: Vec<RegionLink>,
    /// The half bonds that carry heat: each link with its conductance
    /// weight, followed by the outward edge half bond of a sphere on a
    /// lateral surface if it has one ([`super::heat_links`]).
    pub heat_links: Vec<HeatLink>,
}

#[derive(Clone, Copy, PartialEq)]
enum Cell {
    Empty,
    Sphere,
    /// An FE cell: its element (remaining mesh numbering) and its distance
    /// in cells from the nearest sphere (1: a ghost, 2: weights only).
    Fe(u32, u8),
}

/// The particles of element set `set` of `mesh` with radius `radius`; the
/// set's elements leave the mesh, `fe_index[e]` is element e's index in the
/// remaining mesh (`u32::MAX` for the set's). Errors name the set: no
/// sphere fits, or an inverse map fails.
pub fn particle_region(
    mesh: &TetMesh,
    set: &str,
    in_set: &[bool],
    fe_index: &[u32],
    radius: f64,
) -> Result<ParticleRegion, MeshError> {
    let bad = |msg: String| MeshError::InvalidParameter(format!("particles in set `{set}`: {msg}"));
    if !(radius.is_finite() && radius > 0.0) {
        return Err(bad(format!("radius {radius} m must be positive")));
    }
    let corners_of = |e: usize| mesh.tets[e].map(|v| mesh.nodes[v as usize]);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for e in (0..mesh.tets.len()).filter(|&e| in_set[e]) {
        for x in corners_of(e) {
            for a in 0..3 {
                lo[a] = lo[a].min(x[a]);
                hi[a] = hi[a].max(x[a]);
            }
        }
    }
    let d = 2.0 * radius;
    // The set's cells (as lattice_in_element_set), two more on each side.
    let n_set: [usize; 3] = std::array::from_fn(|a| ((hi[a] - lo[a]) / d).ceil().max(1.0) as usize);
    let lo: [f64; 3] = std::array::from_fn(|a| lo[a] - 2.0 * d);
    let n: [usize; 3] = std::array::from_fn(|a| n_set[a] + 4);
    let hi: [f64; 3] = std::array::from_fn(|a| lo[a] + d * n[a] as f64);
    let at = |c: [usize; 3]| c[0] + n[0] * (c[1] + n[1] * c[2]);
    let centre = |c: [usize; 3]| -> [f64; 3] {
        std::array::from_fn(|a| lo[a] + radius * (2 * c[a] + 1) as f64)
    };
    let mut cells = vec![Cell::Empty; n[0] * n[1] * n[2]];
    let mut sphere_elem = vec![u32::MAX; cells.len()];
    // Per cell, the remaining elements whose boxes reach it (to locate points).
    let mut near: Vec<Vec<u32>> = vec![Vec::new(); cells.len()];
    for e in 0..mesh.tets.len() {
        let t = corners_of(e);
        let range = |a: usize| {
            let (mut l, mut h) = (f64::INFINITY, f64::NEG_INFINITY);
            for x in &t {
                l = l.min(x[a]);
                h = h.max(x[a]);
            }
            let first = ((l - lo[a]) / d - 0.5).ceil().max(0.0) as i64;
            let last = (((h - lo[a]) / d - 0.5).floor() as i64).min(n[a] as i64 - 1);
            let box_first = ((l - lo[a]) / d).floor().max(0.0) as i64;
            let box_last = (((h - lo[a]) / d).floor() as i64).min(n[a] as i64 - 1);
            (first, last, box_first, box_last)
        };
        let r = [range(0), range(1), range(2)];
        if r.iter().any(|q| q.2 > q.3) {
            continue;
        }
        let planes = TetPlanes::new(&t);
        for k in r[2].2..=r[2].3 {
            for j in r[1].2..=r[1].3 {
                for i in r[0].2..=r[0].3 {
                    let c = [i, j, k].map(|v| v as usize);
                    if !in_set[e] {
                        near[at(c)].push(fe_index[e]);
                    }
                    let inside = (0..3).all(|a| [i, j, k][a] >= r[a].0 && [i, j, k][a] <= r[a].1);
                    if !inside || !planes.contains(centre(c), 1e-12 * d) {
                        continue;
                    }
                    // A centre on a face shared with the set is the set's; else the lowest element's.
                    let cell = &mut cells[at(c)];
                    if in_set[e] {
                        *cell = Cell::Sphere;
                        let at_c = &mut sphere_elem[at(c)];
                        *at_c = (*at_c).min(e as u32);
                    } else if *cell == Cell::Empty {
                        *cell = Cell::Fe(fe_index[e], 0);
                    }
                }
            }
        }
    }
    // Distances of the FE cells from the spheres (Chebyshev, up to 2).
    let ni = n.map(|v| v as i64);
    let snapshot = cells.clone();
    for k in 0..ni[2] {
        for j in 0..ni[1] {
            for i in 0..ni[0] {
                let c = [i, j, k].map(|v| v as usize);
                let Cell::Fe(e, _) = snapshot[at(c)] else {
                    continue;
                };
                let mut dist = 0u8;
                for dz in -2i64..=2 {
                    for dy in -2i64..=2 {
                        for dx in -2i64..=2 {
                            let q = [i + dx, j + dy, k + dz];
                            if (0..3).any(|a| q[a] < 0 || q[a] >= ni[a]) {
                                continue;
                            }
                            if snapshot[at(q.map(|v| v as usize))] == Cell::Sphere {
                                let s = dx.abs().max(dy.abs()).max(dz.abs()) as u8;
                                dist = if dist == 0 { s } else { dist.min(s) };
                            }
                        }
                    }
                }
                cells[at(c)] = if dist == 0 {
                    Cell::Empty
                } else {
                    Cell::Fe(e, dist)
                };
            }
        }
    }
    let cell_of = |x: [f64; 3]| -> [usize; 3] {
        std::array::from_fn(|a| ((x[a] - lo[a]) / d - 0.5).round() as usize)
    };
    let lattice = cubic_lattice_where(lo, hi, radius, false, |x| {
        cells[at(cell_of(x))] != Cell::Empty
    })?;
    // Spheres numbered in cell order; every lattice member's cell.
    let member: Vec<[usize; 3]> = lattice.centres.iter().map(|&x| cell_of(x)).collect();
    let mut sphere_of = vec![u32::MAX; member.len()];
    let mut centres = Vec::new();
    let mut source_elem = Vec::new();
    for (p, c) in member.iter().enumerate() {
        if cells[at(*c)] == Cell::Sphere {
            sphere_of[p] = centres.len() as u32;
            centres.push(lattice.centres[p]);
            source_elem.push(sphere_elem[at(*c)]);
        }
    }
    if centres.is_empty() {
        return Err(bad(format!(
            "no sphere of radius {radius} m has its centre in the set (radius too large)"
        )));
    }
    // The remaining mesh's element e's corners.
    let mut fe_corners: Vec<[u32; 4]> = vec![[0; 4]; mesh.tets.len()];
    for (e, &ne) in fe_index.iter().enumerate() {
        if ne != u32::MAX {
            fe_corners[ne as usize] = mesh.tets[e];
        }
    }
    let nodes_of = |fe: u32| fe_corners[fe as usize].map(|v| Vector3::from(mesh.nodes[v as usize]));
    // The remaining element among `cands` that holds the point `mid` of an element face, seen
    // from `toward`; if none does (the interface cuts the bond elsewhere), `elem` extended.
    let locate = |cands: &[u32], mid: &Vector3<f64>, toward: &Vector3<f64>, elem: u32| {
        let probe = mid + (toward - mid) * 1e-6;
        cands
            .iter()
            .find_map(|&fe| {
                let t = nodes_of(fe).map(|v| [v.x, v.y, v.z]);
                TetPlanes::new(&t)
                    .contains([probe.x, probe.y, probe.z], 1e-9 * d)
                    .then(|| tet4_ghost(&nodes_of(fe), mid, fe as usize).ok())
                    .flatten()
            })
            .unwrap_or_else(|| extended(&nodes_of(elem), mid, elem))
    };
    let mut bonds = Vec::new();
    let mut links = Vec::new();
    let mut heat_links = Vec::new();
    for b in &lattice.bonds {
        let (i, j) = (b.i as usize, b.j as usize);
        let (si, sj) = (sphere_of[i], sphere_of[j]);
        if si != u32::MAX && sj != u32::MAX {
            bonds.push(LatticeBond { i: si, j: sj, ..*b });
            continue;
        }
        let (s, g) = match (si != u32::MAX, sj != u32::MAX) {
            (true, false) => (i, j),
            (false, true) => (j, i),
            _ => continue,
        };
        // seed 002 eq 5: the ghost x_g = x_b − 2 r n is the cell one step from sphere b along
        // the bond's direction n out of the set, when a remaining element holds its centre.
        let Cell::Fe(ghost_elem, 1) = cells[at(member[g])] else {
            continue;
        };
        let xs = Vector3::from(lattice.centres[s]);
        let xg = Vector3::from(lattice.centres[g]);
        let ghost = tet4_ghost(&nodes_of(ghost_elem), &xg, ghost_elem as usize)
            .map_err(|e| bad(format!("ghost at {:?}: {e}", lattice.centres[g])))?;
        // The midpoint, on the interface: the remaining element that holds it, seen from the ghost's side.
        let mid = (xs + xg) * 0.5;
        let point = locate(&near[at(member[g])], &mid, &xg, ghost_elem);
        let link = RegionLink {
            sphere: sphere_of[s],
            ghost_elem,
            ghost_shape: to4(&ghost.shape),
            point_elem: point.elem as u32,
            point_shape: to4(&point.shape),
            kind: b.kind,
            // Half bond: twice the stiffness (validation::fede_coupling docs).
            weight: 2.0 * b.weight,
        };
        // Heat: the outward edge half bond of a sphere on a lateral surface (heat_links docs).
        let cs = member[s].map(|v| v as i64);
        let offset = |c: [usize; 3]| std::array::from_fn(|a| c[a] as i64 - cs[a]);
        let cell_at = |o: [i64; 3]| at(std::array::from_fn(|a| (cs[a] + o[a]) as usize));
        let beside = |o: [i64; 3]| match cells[cell_at(o)] {
            Cell::Empty => Beside::Empty,
            Cell::Sphere => Beside::Sphere,
            Cell::Fe(_, 1) => Beside::Ghost,
            Cell::Fe(..) => Beside::Fe,
        };
        let mut heat = HeatLink {
            sphere: link.sphere,
            point_elem: link.point_elem,
            point_shape: link.point_shape,
            kind: link.kind,
            weight: link.weight,
        };
        let outward = match outward_edge(offset(member[g]), beside) {
            Some((star, p)) => {
                let mut across = [0; 3];
                across[p] = star[p];
                let mid = xs + Vector3::from(star.map(|c| c as f64)) * radius;
                let Cell::Fe(elem, _) = cells[cell_at(across)] else {
                    unreachable!("outward_edge checked a ghost's cell across the interface")
                };
                let inner = Vector3::from(centre(std::array::from_fn(|a| {
                    (cs[a] + across[a]) as usize
                })));
                let point = locate(&near[cell_at(across)], &mid, &inner, elem);
                let (inward, out) = split_weights(b.weight);
                heat.weight = inward;
                Some(HeatLink {
                    point_elem: point.elem as u32,
                    point_shape: to4(&point.shape),
                    weight: out,
                    ..heat.clone()
                })
            }
            None => None,
        };
        heat_links.push(heat);
        heat_links.extend(outward);
        links.push(link);
    }
    Ok(ParticleRegion {
        radius,
        centres,
        source_elem,
        bonds,
        links,
        heat_links,
    })
}

fn to4(v: &[f64]) -> [f64; 4] {
    [v[0], v[1], v[2], v[3]]
}

/// The linear shape functions of Tet4 `nodes` at `x`, outside it too.
fn extended(
    nodes: &[Vector3<f64>; 4],
    x: &Vector3<f64>,
    elem: u32,
) -> crate::mechanics::ghost::Ghost {
    let e = nalgebra::Matrix3::from_columns(&[
        nodes[1] - nodes[0],
        nodes[2] - nodes[0],
        nodes[3] - nodes[0],
    ]);
    // A remaining element of a validated mesh has positive volume.
    let l = e.try_inverse().unwrap_or_else(nalgebra::Matrix3::zeros) * (x - nodes[0]);
    crate::mechanics::ghost::Ghost {
        elem: elem as usize,
        shape: vec![1.0 - l.x - l.y - l.z, l.x, l.y, l.z],
        grad: Vec::new(),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;
    use crate::mesh::without::without_elements;

    /// A bar 0..12r × 0..4r × 0..4r, elements of side r, the middle third
    /// in x (4r..8r) as particles: the mesh, its remaining elements, the
    /// particles.
    pub(crate) fn bar(r: f64) -> (TetMesh, TetMesh, ParticleRegion) {
        let mut m = box_mesh([0.0; 3], [12.0 * r, 4.0 * r, 4.0 * r], r).unwrap();
        m.add_box_set("middle", [4.0 * r, 0.0, 0.0], [8.0 * r, 4.0 * r, 4.0 * r])
            .unwrap();
        let mut in_set = vec![false; m.tets.len()];
        m.elem_sets["middle"]
            .iter()
            .for_each(|&e| in_set[e as usize] = true);
        let (fe, index) = without_elements(&m, &in_set);
        let region = particle_region(&m, "middle", &in_set, &index, r).unwrap();
        (m, fe, region)
    }

    #[test]
    fn middle_of_a_bar_gives_interior_weights_at_the_interface() {
        let r = 1e-3;
        let (_, fe, region) = bar(r);
        // 2 × 2 × 2 spheres of diameter 2r fill 4r × 4r × 4r.
        assert_eq!(region.centres.len(), 8);
        // Links: each sphere on an interface (x faces) to its ghosts beyond it.
        assert!(!region.links.is_empty());
        for l in &region.links {
            let s = Vector3::from(region.centres[l.sphere as usize]);
            let t = fe.tets[l.point_elem as usize].map(|v| Vector3::from(fe.nodes[v as usize]));
            let p: Vector3<f64> = (0..4).map(|k| t[k] * l.point_shape[k]).sum();
            // The midpoint is on the interface planes x = 4r or 8r, one radius from the sphere along x.
            assert!(
                (p.x - 4.0 * r).abs() < 1e-12 || (p.x - 8.0 * r).abs() < 1e-12,
                "{p:?}"
            );
            assert!(((p - s).x.abs() - r).abs() < 1e-12);
            assert!(l.point_shape.iter().all(|&v| v > -1e-9));
            assert!(l.ghost_shape.iter().all(|&v| v > -1e-9));
        }
        // Face links along x of an interface sphere: the sphere has its inner neighbour and the
        // ghost its far FE neighbour, so the lattice weight is 1 (half bond 2).
        let face: Vec<&RegionLink> = region
            .links
            .iter()
            .filter(|l| l.kind == BondKind::Face)
            .collect();
        assert_eq!(face.len(), 8);
        assert!(face.iter().all(|l| l.weight == 2.0));
    }

    /// Patch test of the links: under the uniform strain of uniaxial stress,
    /// every sphere with all its neighbours (bonds or links) is in
    /// equilibrium: each link, the sphere's half of a bond of twice the
    /// stiffness to the element's point at the midpoint, carries exactly the
    /// force of the lattice bond it replaces.
    #[test]
    fn links_balance_the_bonds_under_uniform_strain() {
        use crate::mechanics::bond::{bond_forces, BondState, BondStiffness};
        use crate::mechanics::interface_link::{advance_link, LinkEnds};
        let r = 1e-3;
        let mut m = box_mesh([0.0; 3], [12.0 * r; 3], r).unwrap();
        m.add_box_set("middle", [4.0 * r, 0.0, 0.0], [8.0 * r, 12.0 * r, 12.0 * r])
            .unwrap();
        let mut in_set = vec![false; m.tets.len()];
        m.elem_sets["middle"]
            .iter()
            .for_each(|&e| in_set[e as usize] = true);
        let (fe, index) = without_elements(&m, &in_set);
        let region = particle_region(&m, "middle", &in_set, &index, r).unwrap();
        assert_eq!(region.centres.len(), 72);
        let (e, nu) = (1e-4, 0.23);
        let u = |x: &Vector3<f64>| Vector3::new(e * x.x, -nu * e * x.y, -nu * e * x.z);
        let k = BondStiffness::seed002(1e9, nu, r).unwrap();
        let p0: Vec<Vector3<f64>> = region.centres.iter().map(|&c| Vector3::from(c)).collect();
        let px: Vec<Vector3<f64>> = p0.iter().map(|p| p + u(p)).collect();
        // One step of dt = 1 from the reference: velocities are the displacements.
        let pv: Vec<Vector3<f64>> = p0.iter().map(u).collect();
        let pw = vec![Vector3::zeros(); p0.len()];
        let mut state: Vec<BondState> = (region.bonds.iter())
            .map(|b| BondState::new(&p0[b.i as usize], &p0[b.j as usize]))
            .collect();
        let (mut f, mut mom) = (
            vec![Vector3::zeros(); p0.len()],
            vec![Vector3::zeros(); p0.len()],
        );
        bond_forces(
            &region.bonds,
            &mut state,
            &k,
            &px,
            &pv,
            &pw,
            1.0,
            None,
            &mut f,
            &mut mom,
        );
        let x0: Vec<Vector3<f64>> = fe.nodes.iter().map(|&c| Vector3::from(c)).collect();
        let at = |elem: u32, shape: &[f64; 4], a: &dyn Fn(&Vector3<f64>) -> Vector3<f64>| {
            let t = fe.tets[elem as usize];
            (0..4)
                .map(|q| a(&x0[t[q] as usize]) * shape[q])
                .sum::<Vector3<f64>>()
        };
        let mut linked = vec![false; p0.len()];
        for l in &region.links {
            let s = l.sphere as usize;
            linked[s] = true;
            let g0 = at(l.ghost_elem, &l.ghost_shape, &|x| *x);
            let mut st = BondState::new(&p0[s], &g0);
            let ends = LinkEnds {
                sphere_x: px[s],
                sphere_v: pv[s],
                sphere_w: Vector3::zeros(),
                ghost_x: at(l.ghost_elem, &l.ghost_shape, &|x| x + u(x)),
                ghost_v: at(l.ghost_elem, &l.ghost_shape, &u),
                point_v: at(l.point_elem, &l.point_shape, &u),
            };
            let kind = l.kind as usize;
            let (kn, ks) = (k.normal[kind] * l.weight, k.tangential[kind] * l.weight);
            f[s] += advance_link(&mut st, kn, ks, &ends, 1.0, 0.0).0;
        }
        // The spheres of the inner columns that have links. (Within two rows of a lateral face
        // the lattice's surface weights leave a sphere unbalanced under uniform strain, links
        // or not: they make the cells' energy right, not each sphere's equilibrium.)
        let scale = k.normal[0] * e * 2.0 * r;
        let mut checked = 0;
        for (s, c) in p0.iter().enumerate() {
            let inner = (1..3).all(|a| c[a] > 4.0 * r && c[a] < 8.0 * r);
            if inner && linked[s] {
                assert!(
                    f[s].norm() < 1e-9 * scale,
                    "sphere {s} at {c:?}: {:?}",
                    f[s]
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 8);
    }

    /// The heat half bonds in a uniform gradient across the interface: each
    /// sphere's heat balance is that of its lattice bonds, and the heat
    /// they give the interface face, shared by bilinear hats on the grid of
    /// the spheres' squares (a Hex8 face), is the uniform flux's share of
    /// every grid node: (2r)² inside, half on the face's edges, a quarter at
    /// its corners. The mechanical links' weights put too little at the
    /// edges.
    #[test]
    fn heat_links_give_the_face_the_uniform_flux() {
        let r = 1e-3;
        // 12r × 8r × 6r, elements of 2r, the middle third (4 × 4 × 3 spheres) as particles.
        let mut m = box_mesh([0.0; 3], [24.0 * r, 8.0 * r, 6.0 * r], 2.0 * r).unwrap();
        m.add_box_set("middle", [8.0 * r, -1.0, -1.0], [16.0 * r, 1.0, 1.0])
            .unwrap();
        let mut in_set = vec![false; m.tets.len()];
        m.elem_sets["middle"]
            .iter()
            .for_each(|&e| in_set[e as usize] = true);
        let (fe, index) = without_elements(&m, &in_set);
        let region = particle_region(&m, "middle", &in_set, &index, r).unwrap();
        assert_eq!(region.centres.len(), 48);
        // T = G x; a link of weight w carries g = h w, h = 1 (k = 5/(2r)), from its point.
        let grad = 3.0;
        let t = |x: &Vector3<f64>| grad * x.x;
        let point = |elem: u32, shape: &[f64; 4]| -> Vector3<f64> {
            let n = fe.tets[elem as usize];
            (0..4)
                .map(|q| Vector3::from(fe.nodes[n[q] as usize]) * shape[q])
                .sum()
        };
        let face = |links: &[(u32, u32, [f64; 4], f64)]| {
            // Heat into each sphere, and the heat each node (j, k) of the 2r grid on x = 8r gets.
            let mut sphere = vec![0.0; region.centres.len()];
            let mut node = [[0.0f64; 4]; 5];
            for &(s, elem, shape, w) in links {
                let p = point(elem, &shape);
                let c = Vector3::from(region.centres[s as usize]);
                let q = w * (t(&p) - t(&c));
                sphere[s as usize] += q;
                if (p.x - 8.0 * r).abs() > 1e-9 * r {
                    continue;
                }
                for (j, row) in node.iter_mut().enumerate() {
                    for (k, v) in row.iter_mut().enumerate() {
                        let hat = |a: f64, b: f64| (1.0 - (a - b).abs() / (2.0 * r)).max(0.0);
                        *v -= q * hat(p.y, 2.0 * r * j as f64) * hat(p.z, 2.0 * r * k as f64);
                    }
                }
            }
            (sphere, node)
        };
        let heat: Vec<_> = (region.heat_links.iter())
            .map(|l| (l.sphere, l.point_elem, l.point_shape, l.weight))
            .collect();
        let mech: Vec<_> = (region.links.iter())
            .map(|l| (l.sphere, l.point_elem, l.point_shape, l.weight))
            .collect();
        let (sphere_heat, node_heat) = face(&heat);
        let (sphere_mech, node_mech) = face(&mech);
        // The uniform flux k G over (2r)²: 10 half bonds' worth of a sphere, 10 h G r.
        let cell = 10.0 * grad * r;
        let share = |j: usize, k: usize| {
            let edge = |i: usize, n: usize| if i == 0 || i == n { 0.5 } else { 1.0 };
            cell * edge(j, 4) * edge(k, 3)
        };
        let mut worst_mech: f64 = 0.0;
        for j in 0..5 {
            for k in 0..4 {
                let e = (node_heat[j][k] - share(j, k)).abs();
                assert!(
                    e < 1e-12 * cell,
                    "node ({j}, {k}): {} vs {}",
                    node_heat[j][k],
                    share(j, k)
                );
                worst_mech = worst_mech.max((node_mech[j][k] - share(j, k)).abs());
            }
        }
        assert!(worst_mech > 0.05 * cell, "{worst_mech}");
        // Each sphere's links carry the same heat with either weights (its lattice bonds' heat).
        for (a, b) in sphere_heat.iter().zip(&sphere_mech) {
            assert!((a - b).abs() < 1e-12 * cell, "{a} {b}");
        }
    }

    #[test]
    fn radius_too_large_is_an_error_naming_the_set() {
        let r = 1e-3;
        let (m, _, _) = bar(r);
        let mut in_set = vec![false; m.tets.len()];
        m.elem_sets["middle"]
            .iter()
            .for_each(|&e| in_set[e as usize] = true);
        let (_, index) = without_elements(&m, &in_set);
        let err = particle_region(&m, "middle", &in_set, &index, 5.0 * r).unwrap_err();
        assert!(err.to_string().contains("`middle`"), "{err}");
    }
}
