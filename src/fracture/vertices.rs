//! The vertex of the continuous mesh behind each node copy of a jointed
//! body (seed 004 sec 2.7, Fig 2: a joint ties two faces that were one, so
//! its corner pairs a[i], b[i] were one node). Union-find over every
//! joint, broken or not, numbers each copy by the lowest copy of its
//! vertex; two tets of the body shared a vertex of the continuous mesh
//! when they have a corner of the same class. Exact wherever the tets
//! around a vertex are joined face to face (a manifold mesh); tets that met
//! only at a pinched vertex or edge count as apart. Pure.

/// The class (lowest node joined to it) of each of `n` nodes tied by the
/// corner pairs `ties`; a node tied to none is its own class.
pub fn vertex_classes(n: usize, ties: impl IntoIterator<Item = (u32, u32)>) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], g: u32) -> u32 {
        let mut r = g;
        while parent[r as usize] != r {
            r = parent[r as usize];
        }
        let mut x = g;
        while x != r {
            let next = parent[x as usize];
            parent[x as usize] = r;
            x = next;
        }
        r
    }
    for (a, b) in ties {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        // The lower root stays, so each class is named by its lowest node.
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    }
    (0..n as u32).map(|g| root(&mut parent, g)).collect()
}

/// The class (lowest id joined to it) of every id that appears in the
/// corner pairs `ties`, for ids scattered over a large range (global node
/// ids): the union-find of [`vertex_classes`] over the ids numbered
/// densely in ascending order, so the lowest dense index is the lowest id.
pub fn id_classes(
    ties: impl IntoIterator<Item = (u32, u32)> + Clone,
) -> std::collections::HashMap<u32, u32> {
    let mut ids: Vec<u32> = ties.clone().into_iter().flat_map(|(a, b)| [a, b]).collect();
    ids.sort_unstable();
    ids.dedup();
    let dense = |g: u32| ids.binary_search(&g).expect("an id of the ties") as u32;
    let class = vertex_classes(
        ids.len(),
        ties.into_iter().map(|(a, b)| (dense(a), dense(b))),
    );
    ids.iter()
        .zip(&class)
        .map(|(&g, &c)| (g, ids[c as usize]))
        .collect()
}

/// Whether two tets (corners as node classes) shared no vertex.
pub fn share_no_vertex(a: &[u32; 4], b: &[u32; 4]) -> bool {
    a.iter().all(|v| !b.contains(v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fracture::insert::make_discontinuous;

    #[test]
    fn classes_are_the_continuous_vertices() {
        let m = crate::mesh::generate::box_mesh([0.0; 3], [1.0, 1.0, 2.0], 0.5).unwrap();
        let j = make_discontinuous(&m.nodes, &m.tets, &vec![true; m.tets.len()]);
        let ties = j
            .joints
            .iter()
            .flat_map(|f| f.a.iter().zip(&f.b).map(|(&a, &b)| (a, b)));
        let class = vertex_classes(j.nodes.len(), ties);
        // Two copies are in one class exactly when they came from one
        // vertex: the box is a manifold, every vertex's tets face-joined.
        for x in 0..j.nodes.len() {
            for y in 0..j.nodes.len() {
                assert_eq!(class[x] == class[y], j.origin[x] == j.origin[y]);
            }
        }
        let of = |t: usize| j.tets[t].map(|v| class[v as usize]);
        for s in 0..m.tets.len() {
            for t in 0..m.tets.len() {
                let shared = m.tets[s].iter().any(|v| m.tets[t].contains(v));
                assert_eq!(share_no_vertex(&of(s), &of(t)), !shared);
            }
        }
    }

    #[test]
    fn scattered_ids_take_their_lowest_tied_id() {
        let c = id_classes([(900, 40), (7, 900), (5000, 6000)]);
        assert_eq!(c.len(), 5);
        for g in [7, 40, 900] {
            assert_eq!(c[&g], 7);
        }
        assert_eq!(c[&5000], 5000);
        assert_eq!(c[&6000], 5000);
        assert!(id_classes(std::iter::empty::<(u32, u32)>()).is_empty());
    }

    #[test]
    fn untied_nodes_are_their_own_class() {
        assert_eq!(vertex_classes(4, [(3, 1), (2, 3)]), vec![0, 1, 1, 1]);
        assert_eq!(vertex_classes(3, []), vec![0, 1, 2]);
    }
}
