//! Joint insertion (seed 004 sec 2.7, Fig 2): a tet mesh made discontinuous
//! on a set of its tets. Every tet of the set gets its own four nodes, and
//! a joint ties each pair of faces that were one face of the continuous
//! mesh, where at least one of the two tets is in the set. Tets outside the
//! set keep their shared nodes. Works on any list of tets (a body, or the
//! tets a rank owns with their neighbours), so it never needs the whole
//! mesh. Free of MPI and PETSc.

use std::collections::HashMap;

/// The two faces of one joint: corners in the new numbering, `a[i]` and
/// `b[i]` at the same place; `a` is ordered counter-clockwise seen from
/// tet `tets[1]` (its normal points out of `tets[0]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointFaces {
    pub a: [u32; 3],
    pub b: [u32; 3],
    /// The tets on the a and b sides.
    pub tets: [u32; 2],
    /// Reference area (m²).
    pub area: f64,
}

/// A mesh made discontinuous.
#[derive(Debug, Clone, PartialEq)]
pub struct Jointed {
    /// Node coordinates in the new numbering.
    pub nodes: Vec<[f64; 3]>,
    /// Each new node's node of the continuous mesh.
    pub origin: Vec<u32>,
    /// The tets in the new numbering (same order as given).
    pub tets: Vec<[u32; 4]>,
    /// One joint per face two tets shared (at least one in the set), in
    /// the order of the faces' sorted corner ids: the same on every rank.
    pub joints: Vec<JointFaces>,
}

/// A face two tets share: its sorted corners, and (tet, local face) of
/// the lower and the higher tet.
type SharedFace = ([u32; 3], (u32, usize), (u32, usize));

/// Local faces of a tet: the three corners opposite corner k, oriented
/// outwards for a positively oriented tet.
pub(crate) const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The joint of the face `fa` of tet `ta` shared with tet `tb` (`ta` <
/// `tb`): its corners in the new numbering (`new_a`, `new_b`: the two
/// tets' corners there), `a` counter-clockwise seen from `tb`.
pub(crate) fn joint_faces(
    nodes: &[[f64; 3]],
    tets: &[[u32; 4]],
    (ta, fa): (u32, usize),
    tb: u32,
    new_a: [u32; 4],
    new_b: [u32; 4],
) -> JointFaces {
    let (ta_u, tb_u) = (ta as usize, tb as usize);
    let mut loc = FACES[fa];
    let x = |g: u32| nodes[g as usize];
    let g: [u32; 3] = loc.map(|l| tets[ta_u][l]);
    // Orient a's corners so that the normal points out of tet a.
    let nrm = cross(sub(x(g[1]), x(g[0])), sub(x(g[2]), x(g[0])));
    let apex = x(tets[ta_u][fa]);
    if dot(nrm, sub(apex, x(g[0]))) > 0.0 {
        loc.swap(1, 2);
    }
    let g: [u32; 3] = loc.map(|l| tets[ta_u][l]);
    let a = loc.map(|l| new_a[l]);
    let b = g.map(|gi| {
        let k = tets[tb_u]
            .iter()
            .position(|&c| c == gi)
            .unwrap_or_else(|| unreachable!("a shared face's corner is a corner of both tets"));
        new_b[k]
    });
    let n = cross(sub(x(g[1]), x(g[0])), sub(x(g[2]), x(g[0])));
    JointFaces {
        a,
        b,
        tets: [ta, tb],
        area: 0.5 * dot(n, n).sqrt(),
    }
}

/// Make the tets of `in_set` discontinuous (`in_set[t]` per tet).
pub fn make_discontinuous(nodes: &[[f64; 3]], tets: &[[u32; 4]], in_set: &[bool]) -> Jointed {
    assert_eq!(tets.len(), in_set.len());
    let mut origin: Vec<u32> = Vec::new();
    let mut shared: HashMap<u32, u32> = HashMap::new();
    let mut new_tets = Vec::with_capacity(tets.len());
    for (t, tet) in tets.iter().enumerate() {
        let mut nt = [0u32; 4];
        for (k, &g) in tet.iter().enumerate() {
            nt[k] = if in_set[t] {
                origin.push(g);
                (origin.len() - 1) as u32
            } else {
                *shared.entry(g).or_insert_with(|| {
                    origin.push(g);
                    (origin.len() - 1) as u32
                })
            };
        }
        new_tets.push(nt);
    }
    // Faces by their sorted corners: (tet, local face).
    let mut faces: HashMap<[u32; 3], Vec<(u32, usize)>> = HashMap::new();
    for (t, tet) in tets.iter().enumerate() {
        for (f, loc) in FACES.iter().enumerate() {
            let mut key = [tet[loc[0]], tet[loc[1]], tet[loc[2]]];
            key.sort_unstable();
            faces.entry(key).or_default().push((t as u32, f));
        }
    }
    let mut shared_faces: Vec<SharedFace> = faces
        .into_iter()
        .filter_map(|(k, v)| match v.as_slice() {
            [p, q] if in_set[p.0 as usize] || in_set[q.0 as usize] => {
                let (p, q) = if p.0 < q.0 { (*p, *q) } else { (*q, *p) };
                Some((k, p, q))
            }
            _ => None,
        })
        .collect();
    shared_faces.sort_unstable_by_key(|s| s.0);
    let joints = shared_faces
        .into_iter()
        .map(|(_, a, (tb, _))| {
            let (ta, tb_u) = (a.0 as usize, tb as usize);
            joint_faces(nodes, tets, a, tb, new_tets[ta], new_tets[tb_u])
        })
        .collect();
    let new_nodes = origin.iter().map(|&g| nodes[g as usize]).collect();
    Jointed {
        nodes: new_nodes,
        origin,
        tets: new_tets,
        joints,
    }
}

/// A body's mesh made discontinuous on the tets of `in_set`, with its
/// named sets carried over: a node set holds every copy of its nodes, a
/// face set the copies on the tet that has the face (the first, for a
/// face two tets share), element sets are unchanged.
pub fn jointed_mesh(
    mesh: &crate::mesh::TetMesh,
    in_set: &[bool],
) -> (crate::mesh::TetMesh, Jointed) {
    let j = make_discontinuous(&mesh.nodes, &mesh.tets, in_set);
    let mut copies: Vec<Vec<u32>> = vec![Vec::new(); mesh.nodes.len()];
    for (new, &old) in j.origin.iter().enumerate() {
        copies[old as usize].push(new as u32);
    }
    let node_sets = mesh
        .node_sets
        .iter()
        .map(|(name, nodes)| {
            let mut v: Vec<u32> = nodes
                .iter()
                .flat_map(|&n| copies[n as usize].iter().copied())
                .collect();
            v.sort_unstable();
            (name.clone(), v)
        })
        .collect();
    let mut tet_of_face: HashMap<[u32; 3], u32> = HashMap::new();
    for (t, tet) in mesh.tets.iter().enumerate() {
        for loc in FACES {
            let mut key = loc.map(|l| tet[l]);
            key.sort_unstable();
            tet_of_face.entry(key).or_insert(t as u32);
        }
    }
    let face_sets = mesh
        .face_sets
        .iter()
        .map(|(name, faces)| {
            let v = faces
                .iter()
                .map(|f| {
                    let mut key = *f;
                    key.sort_unstable();
                    let t = tet_of_face[&key] as usize;
                    f.map(|n| {
                        let k = mesh.tets[t]
                            .iter()
                            .position(|&c| c == n)
                            .expect("a face set's face is a face of a tet");
                        j.tets[t][k]
                    })
                })
                .collect();
            (name.clone(), v)
        })
        .collect();
    let out = crate::mesh::TetMesh {
        nodes: j.nodes.clone(),
        tets: j.tets.clone(),
        body: mesh.body.clone(),
        node_sets,
        face_sets,
        elem_sets: mesh.elem_sets.clone(),
    };
    (out, j)
}

/// The size h of a joint for its stiffness p_f / h: the edge of the
/// equilateral triangle of its area (m).
pub fn joint_size(area: f64) -> f64 {
    (4.0 * area / 3f64.sqrt()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

    #[test]
    fn every_shared_face_of_a_box_becomes_one_joint_of_coincident_faces() {
        let m = box_mesh([0.0; 3], [1.0, 0.5, 0.25], 0.25).unwrap();
        let (nodes, tets) = (&m.nodes, &m.tets);
        let all = vec![true; tets.len()];
        let j = make_discontinuous(nodes, tets, &all);
        assert_eq!(j.nodes.len(), 4 * tets.len());
        // Interior faces: 4 per tet counted once per side, minus the boundary.
        let boundary = m.boundary_faces().len();
        assert_eq!(j.joints.len(), (4 * tets.len() - boundary) / 2);
        let total: f64 = j.joints.iter().map(|f| f.area).sum();
        assert!(total > 0.0);
        for f in &j.joints {
            for i in 0..3 {
                assert_eq!(j.nodes[f.a[i] as usize], j.nodes[f.b[i] as usize]);
                assert_eq!(j.origin[f.a[i] as usize], j.origin[f.b[i] as usize]);
                assert_ne!(f.a[i], f.b[i]);
            }
            // The a face's normal points out of tet a, into tet b.
            let x = |n: u32| j.nodes[n as usize];
            let nrm = cross(sub(x(f.a[1]), x(f.a[0])), sub(x(f.a[2]), x(f.a[0])));
            let centroid = |t: u32| {
                let c = j.tets[t as usize].map(x);
                [0, 1, 2].map(|d| c.iter().map(|p| p[d]).sum::<f64>() / 4.0)
            };
            let ab = sub(centroid(f.tets[1]), centroid(f.tets[0]));
            assert!(dot(nrm, ab) > 0.0);
        }
    }

    #[test]
    fn tets_outside_the_set_keep_their_shared_nodes() {
        let m = box_mesh([0.0; 3], [1.0, 1.0, 1.0], 1.0).unwrap();
        let (nodes, tets) = (&m.nodes, &m.tets);
        let mut set = vec![false; tets.len()];
        set[0] = true;
        let j = make_discontinuous(nodes, tets, &set);
        // Only the faces of tet 0 shared with a neighbour become joints.
        assert!(j.joints.iter().all(|f| f.tets.contains(&0)));
        assert!(!j.joints.is_empty());
        // The others still share: their distinct nodes, plus tet 0's four.
        let mut others: Vec<u32> = tets[1..].iter().flatten().copied().collect();
        others.sort_unstable();
        others.dedup();
        assert_eq!(j.nodes.len(), others.len() + 4);
    }
}
