//! Self-contact of the jointed bodies this rank holds (issue 19): their
//! parts that meet each other after cracks freed them. Each pair is found
//! once, from its lower tet ([`crate::contact::self_search`]): among the
//! own tets of a body held whole here, and for a body split over the ranks
//! also against the ghost copies of its tets on other ranks (the contact
//! ghosts carry a split body's own pieces for it). A pair is a candidate
//! only when its two tets shared no vertex of the continuous mesh (tets
//! that did are held by their joints, or pressed by their crack faces):
//! the vertex classes of a whole body come from the part's joints, a
//! split body's from all its joints in the model, so they name the ghosts'
//! corners too. Pairs then go the way of any penalty pair: planes,
//! balancing, the pair-key sum.

use crate::contact::self_search::find_within;
use crate::contact::{BodyTets, Candidate, OwnAndGhosts};
use crate::fracture::vertices::{share_no_vertex, vertex_classes};
use crate::model::Model;
use crate::parallel::Part;

/// Which bodies search themselves and the vertex class of each part node.
#[derive(Debug, Clone, Default)]
pub(super) struct SelfContact {
    /// The free jointed bodies of the part (global ids, ascending).
    bodies: Vec<u32>,
    /// Per part node: the lowest copy of its vertex of the continuous mesh
    /// (empty without jointed bodies).
    vertex: Vec<u32>,
    /// The free jointed bodies split over the ranks (ascending), each
    /// with its first node's global id and its joints' numbering, which
    /// names each node's vertex of the continuous mesh
    /// ([`crate::model::SourceJoints::origin`], shared: no rank makes an
    /// array of the whole body for it).
    split: Vec<(u32, u32, crate::model::SourceJoints)>,
}

impl SelfContact {
    /// The part's free jointed bodies and their copies' vertices, from
    /// every joint of the part, broken or not (`body_held[b]`: body b
    /// does not move). Sized by the part, nothing of the whole mesh.
    pub(super) fn new(model: &Model, part: &Part, body_held: &[bool]) -> SelfContact {
        let is_split = |b: u32| part.whole_bodies.binary_search(&b).is_err();
        // A split jointed body searches itself on every rank holding tets
        // of it, also one holding none of its joints (tets of the
        // continuum part of a body jointed on a set).
        let split_jointed = |b: u32| {
            is_split(b)
                && matches!(model.bodies[b as usize].source,
                    crate::model::BodySource::Mesh { mesh, .. }
                        if model.meshes[mesh as usize].joints.is_some())
        };
        let mut bodies: Vec<u32> = part
            .joints
            .iter()
            .map(|j| j.body)
            .chain(part.mesh.body.iter().copied().filter(|&b| split_jointed(b)))
            .filter(|&b| !body_held[b as usize])
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        if bodies.is_empty() {
            return SelfContact::default();
        }
        let split: Vec<(u32, u32, crate::model::SourceJoints)> = bodies
            .iter()
            .filter(|&&b| is_split(b))
            .filter_map(|&b| {
                let body = &model.bodies[b as usize];
                let crate::model::BodySource::Mesh { mesh, .. } = body.source else {
                    return None;
                };
                let j = model.meshes[mesh as usize].joints.as_ref()?;
                Some((b, body.node_range.0, j.clone()))
            })
            .collect();
        let ties = part
            .joints
            .iter()
            .filter(|j| !is_split(j.body))
            .flat_map(|j| j.faces.a.iter().copied().zip(j.faces.b.iter().copied()));
        let mut vertex = vertex_classes(part.mesh.nodes.len(), ties);
        // A split body's nodes by their vertex of the continuous mesh.
        for (e, t) in part.mesh.tets.iter().enumerate() {
            let b = part.mesh.body[e];
            if let Ok(i) = split.binary_search_by_key(&b, |s| s.0) {
                let (_, n0, origin) = &split[i];
                for &l in t {
                    vertex[l as usize] = origin.origin(part.node_gid[l as usize] - n0);
                }
            }
        }
        SelfContact {
            vertex,
            bodies,
            split,
        }
    }

    /// The bodies split over the ranks that search themselves (ascending):
    /// the contact ghosts must bring their pieces on other ranks.
    pub(super) fn split_bodies(&self) -> Vec<u32> {
        self.split.iter().map(|s| s.0).collect()
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
        let class = |h: u32| -> Option<[u32; 4]> {
            if h < n_own {
                return Some(og.own.tets[h as usize].map(|l| self.vertex[l as usize]));
            }
            // A ghost: a tet of a split body on another rank.
            let g = (h - n_own) as usize;
            let i = self
                .split
                .binary_search_by_key(&og.ghosts.body[g], |s| s.0)
                .ok()?;
            let (_, n0, origin) = &self.split[i];
            Some(og.ghosts.tets[g].map(|n| origin.origin(og.ghosts.node_gid[n as usize] - n0)))
        };
        find_within(
            tets,
            |b| self.bodies.binary_search(&b).is_ok(),
            |h| og.corners(h),
            |h| og.gid(h),
            |a, b| {
                a < n_own
                    && matches!((class(a), class(b)), (Some(x), Some(y)) if share_no_vertex(&x, &y))
            },
            margin,
        )
    }
}
