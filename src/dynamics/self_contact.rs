//! Self-contact of the jointed bodies this rank holds (issue 19): their
//! parts that meet each other after cracks freed them. A jointed body is
//! held whole by one rank, so its pairs are found there from its own tets,
//! each once ([`crate::contact::self_search`]); a pair is a candidate only
//! when its two tets shared no vertex of the continuous mesh (tets that did
//! are held by their joints, or pressed by their crack faces). Pairs then
//! go the way of any penalty pair: planes, balancing, the pair-key sum.

use crate::contact::self_search::find_within;
use crate::contact::{BodyTets, Candidate, OwnAndGhosts};
use crate::fracture::vertices::{share_no_vertex, vertex_classes};
use crate::parallel::Part;

/// Which bodies search themselves and the vertex class of each part node.
#[derive(Debug, Clone, Default)]
pub(super) struct SelfContact {
    /// The free jointed bodies of the part (global ids, ascending).
    bodies: Vec<u32>,
    /// Per part node: the lowest copy of its vertex of the continuous mesh
    /// (empty without jointed bodies).
    vertex: Vec<u32>,
}

impl SelfContact {
    /// The part's free jointed bodies and their copies' vertices, from
    /// every joint of the part, broken or not (`body_held[b]`: body b
    /// does not move). Sized by the part, nothing of the whole mesh.
    pub(super) fn new(part: &Part, body_held: &[bool]) -> SelfContact {
        let mut bodies: Vec<u32> = part
            .joints
            .iter()
            .map(|j| {
                let e = part
                    .elem_gid
                    .binary_search(&j.faces.tets[0])
                    .expect("a joint's tet is held");
                part.mesh.body[e]
            })
            .filter(|&b| !body_held[b as usize])
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        if bodies.is_empty() {
            return SelfContact::default();
        }
        let ties = part
            .joints
            .iter()
            .flat_map(|j| j.faces.a.iter().copied().zip(j.faces.b.iter().copied()));
        SelfContact {
            vertex: vertex_classes(part.mesh.nodes.len(), ties),
            bodies,
        }
    }

    /// Whether any body here searches itself.
    pub(super) fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }

    /// The self-contact candidates of this rank's jointed bodies among the
    /// tets `tets` of `og` (own tets only: the body is whole here).
    pub(super) fn candidates(
        &self,
        og: &OwnAndGhosts,
        tets: &BodyTets,
        margin: f64,
    ) -> Vec<Candidate> {
        if self.is_empty() {
            return Vec::new();
        }
        let n_own = og.own.len() as u32;
        let class = |h: u32| og.own.tets[h as usize].map(|l| self.vertex[l as usize]);
        find_within(
            tets,
            |b| self.bodies.binary_search(&b).is_ok(),
            |h| og.corners(h),
            |h| og.gid(h),
            |a, b| a < n_own && b < n_own && share_no_vertex(&class(a), &class(b)),
            margin,
        )
    }
}
