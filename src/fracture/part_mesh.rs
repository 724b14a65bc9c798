//! The jointed mesh around a part of a body made discontinuous, made from
//! the continuous mesh and its [`Numbering`] alone (issue 19): a rank
//! holding some tets of a large jointed body makes their copies, the
//! joints at them and the other corners of those joints, and, so that
//! every named set reaches those copies as in the whole-body build
//! ([`super::insert::jointed_mesh`]), the ring of tets touching them.
//! Nothing of the size of the whole jointed body. Free of MPI and PETSc.

use std::collections::HashMap;

use super::insert::{JointFaces, FACES};
use super::numbering::Numbering;
use crate::mesh::TetMesh;

/// The jointed mesh around a part.
#[derive(Debug, Clone, PartialEq)]
pub struct JointedPart {
    /// Every tet with a corner among the part's copies and the joints'
    /// corners, in its own numbering; its sets carried over as
    /// [`super::insert::jointed_mesh`] carries them (a face set's face
    /// only when its first tet is here).
    pub mesh: TetMesh,
    /// Per node of `mesh`: its copy (ascending).
    pub copy: Vec<u32>,
    /// Per node of `mesh`: its node of the continuous mesh.
    pub origin: Vec<u32>,
    /// Per tet of `mesh`: its tet (ascending).
    pub tet: Vec<u32>,
    /// The joints at the copies of the held tets (ascending number): the
    /// number, and the faces with corners in `mesh`'s numbering (tets by
    /// their own numbers).
    pub joints: Vec<(u32, JointFaces)>,
}

impl JointedPart {
    /// The part of the tets `held` (ascending) of the mesh `nodes`,
    /// `tets` (with named sets from `sets`, if any) made discontinuous on
    /// the tets of `in_set`, numbered by `num`; the joints' areas measured
    /// on the nodes `reference` (the same mesh before a rigid motion).
    pub fn new(
        num: &Numbering,
        (nodes, reference): (&[[f64; 3]], &[[f64; 3]]),
        tets: &[[u32; 4]],
        sets: Option<&TetMesh>,
        in_set: &[bool],
        held: &[u32],
    ) -> JointedPart {
        let p = num.part(reference, tets, in_set, held);
        // The copies the part holds: its tets' corners and its joints'.
        let mut wanted: Vec<u32> = p.copies.iter().map(|&(c, _)| c).collect();
        wanted.extend(p.joints.iter().flat_map(|(_, j)| j.a.iter().chain(&j.b)));
        wanted.sort_unstable();
        wanted.dedup();
        // The tets with a corner among them.
        let mut ring: Vec<u32> = Vec::new();
        for &c in &wanted {
            let g = num.origin(c, tets, in_set);
            for &t in num.tets_at(g) {
                if num.tet_copies(t, tets, in_set).contains(&c) {
                    ring.push(t);
                }
            }
        }
        ring.sort_unstable();
        ring.dedup();
        let copies_of_ring: Vec<[u32; 4]> = ring
            .iter()
            .map(|&t| num.tet_copies(t, tets, in_set))
            .collect();
        let mut pairs: Vec<(u32, u32)> = ring
            .iter()
            .zip(&copies_of_ring)
            .flat_map(|(&t, c)| (0..4).map(move |k| (c[k], tets[t as usize][k])))
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        let copy: Vec<u32> = pairs.iter().map(|p| p.0).collect();
        let origin: Vec<u32> = pairs.iter().map(|p| p.1).collect();
        let local = |c: u32| -> u32 {
            copy.binary_search(&c)
                .unwrap_or_else(|_| unreachable!("copy {c} is a corner of a tet here"))
                as u32
        };
        let mut mesh = TetMesh {
            nodes: origin.iter().map(|&g| nodes[g as usize]).collect(),
            tets: copies_of_ring.iter().map(|c| c.map(local)).collect(),
            body: vec![0; ring.len()],
            ..Default::default()
        };
        if let Some(src) = sets {
            mesh.body = ring.iter().map(|&t| src.body[t as usize]).collect();
            let mut at_vertex: HashMap<u32, Vec<u32>> = HashMap::new();
            for (l, &g) in origin.iter().enumerate() {
                at_vertex.entry(g).or_default().push(l as u32);
            }
            mesh.node_sets = src
                .node_sets
                .iter()
                .map(|(name, set)| {
                    let mut v: Vec<u32> = set
                        .iter()
                        .filter_map(|g| at_vertex.get(g))
                        .flatten()
                        .copied()
                        .collect();
                    v.sort_unstable();
                    (name.clone(), v)
                })
                .collect();
            mesh.face_sets = src
                .face_sets
                .iter()
                .map(|(name, faces)| {
                    let v = faces
                        .iter()
                        .filter_map(|f| {
                            // The face's first tet (the lowest with it).
                            let t = num
                                .tets_at(f[0])
                                .iter()
                                .copied()
                                .filter(|&t| f.iter().all(|n| tets[t as usize].contains(n)))
                                .min()?;
                            let i = ring.binary_search(&t).ok()?;
                            Some(f.map(|n| {
                                let k = tets[t as usize]
                                    .iter()
                                    .position(|&c| c == n)
                                    .unwrap_or_else(|| unreachable!("a corner of its tet"));
                                mesh.tets[i][k]
                            }))
                        })
                        .collect();
                    (name.clone(), v)
                })
                .collect();
            mesh.elem_sets = src
                .elem_sets
                .iter()
                .map(|(name, set)| {
                    let v = set
                        .iter()
                        .filter_map(|t| ring.binary_search(t).ok().map(|i| i as u32))
                        .collect();
                    (name.clone(), v)
                })
                .collect();
        }
        let joints = p
            .joints
            .into_iter()
            .map(|(k, j)| {
                (
                    k,
                    JointFaces {
                        a: j.a.map(local),
                        b: j.b.map(local),
                        ..j
                    },
                )
            })
            .collect();
        JointedPart {
            mesh,
            copy,
            origin,
            tet: ring,
            joints,
        }
    }
}

/// The area of the largest joint of a mesh made discontinuous on the
/// tets of `in_set` (`face_mask[t]` bit k: tet t's face opposite corner k
/// is on the boundary): the largest inner face of a tet of the set.
pub fn largest_joint_area(
    nodes: &[[f64; 3]],
    tets: &[[u32; 4]],
    face_mask: &[u8],
    in_set: &[bool],
) -> f64 {
    let mut largest: f64 = 0.0;
    for (t, tet) in tets.iter().enumerate() {
        if !in_set[t] {
            continue;
        }
        for (k, loc) in FACES.iter().enumerate() {
            if face_mask[t] & (1 << k) == 0 {
                let p = loc.map(|l| nodes[tet[l] as usize]);
                largest = largest.max(crate::geometry::polygon_area(&p));
            }
        }
    }
    largest
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fracture::insert::jointed_mesh;
    use crate::mesh::generate::box_mesh;

    /// Held whole, the part is the whole-body build with its sets; held
    /// by thirds, each part's nodes, tets, sets and joints are the whole
    /// build's around it.
    #[test]
    fn parts_are_the_whole_jointed_mesh_around_them() {
        let mut m = box_mesh([0.0; 3], [1.0, 0.5, 0.25], 0.125).unwrap();
        m.elem_sets
            .insert("odd".into(), (1..m.tets.len() as u32).step_by(2).collect());
        let in_set: Vec<bool> = (0..m.tets.len()).map(|t| t % 3 != 1).collect();
        let (whole, j) = jointed_mesh(&m, &in_set);
        let num = Numbering::new(m.nodes.len(), &m.tets, &in_set);
        let n = m.tets.len() as u32;
        let all: Vec<u32> = (0..n).collect();
        let p = JointedPart::new(&num, (&m.nodes, &m.nodes), &m.tets, Some(&m), &in_set, &all);
        assert_eq!(p.mesh, whole);
        assert_eq!(p.origin, j.origin);
        let want: Vec<(u32, JointFaces)> = (0..).zip(j.joints.iter().copied()).collect();
        assert_eq!(p.joints, want);
        for (lo, hi) in [(0, n / 3), (n / 3, 2 * n / 3), (2 * n / 3, n)] {
            let held: Vec<u32> = (lo..hi).collect();
            let p = JointedPart::new(
                &num,
                (&m.nodes, &m.nodes),
                &m.tets,
                Some(&m),
                &in_set,
                &held,
            );
            assert!(p.copy.len() < whole.nodes.len());
            for (l, &c) in p.copy.iter().enumerate() {
                assert_eq!(p.mesh.nodes[l], whole.nodes[c as usize]);
            }
            for (i, &t) in p.tet.iter().enumerate() {
                assert_eq!(
                    p.mesh.tets[i].map(|l| p.copy[l as usize]),
                    whole.tets[t as usize]
                );
            }
            assert!(held.iter().all(|t| p.tet.binary_search(t).is_ok()));
            for (name, set) in &whole.node_sets {
                let got: Vec<u32> = p.mesh.node_sets[name]
                    .iter()
                    .map(|&l| p.copy[l as usize])
                    .collect();
                let want: Vec<u32> = set
                    .iter()
                    .copied()
                    .filter(|c| p.copy.binary_search(c).is_ok())
                    .collect();
                assert_eq!(got, want, "node set {name}");
            }
            for (name, set) in &whole.elem_sets {
                let got: Vec<u32> = p.mesh.elem_sets[name]
                    .iter()
                    .map(|&i| p.tet[i as usize])
                    .collect();
                let want: Vec<u32> = set
                    .iter()
                    .copied()
                    .filter(|t| p.tet.binary_search(t).is_ok())
                    .collect();
                assert_eq!(got, want, "element set {name}");
            }
            for (name, faces) in &whole.face_sets {
                let got: Vec<[u32; 3]> = p.mesh.face_sets[name]
                    .iter()
                    .map(|f| f.map(|l| p.copy[l as usize]))
                    .collect();
                let here = |c: &u32| p.copy.binary_search(c).is_ok();
                assert!(faces
                    .iter()
                    .filter(|f| f.iter().all(here))
                    .all(|f| got.contains(f)));
                assert!(got.iter().all(|f| faces.contains(f)), "face set {name}");
            }
            for (k, jf) in &p.joints {
                let w = j.joints[*k as usize];
                assert_eq!(jf.a.map(|l| p.copy[l as usize]), w.a);
                assert_eq!(jf.b.map(|l| p.copy[l as usize]), w.b);
            }
        }
    }

    /// The largest joint of a box is its largest inner face of a jointed tet.
    #[test]
    fn the_largest_joint_is_the_largest_inner_face() {
        let m = box_mesh([0.0; 3], [1.0, 0.5, 0.25], 0.125).unwrap();
        let in_set: Vec<bool> = (0..m.tets.len()).map(|t| t % 3 != 1).collect();
        let bt = crate::contact::BoundaryTets::new(&m);
        let j = crate::fracture::make_discontinuous(&m.nodes, &m.tets, &in_set);
        let want = j.joints.iter().map(|f| f.area).fold(0.0, f64::max);
        let got = largest_joint_area(&m.nodes, &m.tets, &bt.mask, &in_set);
        assert!((got - want).abs() <= 1e-14 * want, "{got} against {want}");
    }
}
