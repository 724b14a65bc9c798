//! A rank's tets as the contact search reads them: its own part, or the
//! ghost copies of other ranks' pieces ([`crate::parallel::ghosts`]), each
//! tet with its global id, body, material, boundary faces and reference
//! volume, each node with its global id, owner, PETSc number and current
//! position; and the search over own and ghost tets together.

use super::search::{BodyTets, Candidate, ContactSearch, SearchOptions, TetRole};
use super::{tet_shapes_contact, ContactPair, PairDofs, TetFaces};
use crate::geometry::TetShape;

/// Tets with their nodes, as the contact search reads them: a rank's own
/// part, or the ghost copies of other ranks' pieces.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ContactTets {
    /// Per tet: global element id.
    pub gid: Vec<u32>,
    /// Per tet: global body id.
    pub body: Vec<u32>,
    /// Per tet: material.
    pub material: Vec<u32>,
    /// Per tet: its faces on its body's boundary (bit i: opposite node i).
    pub mask: Vec<u8>,
    /// Per tet: reference volume (m³).
    pub volume0: Vec<f64>,
    /// Per tet: its nodes (indices into the node arrays).
    pub tets: Vec<[u32; 4]>,
    /// Per node: global id.
    pub node_gid: Vec<u32>,
    /// Per node: owning rank.
    pub node_owner: Vec<u32>,
    /// Per node: PETSc number.
    pub node_petsc: Vec<u32>,
    /// Per node: on its body's boundary.
    pub node_boundary: Vec<bool>,
    /// Per node: current position.
    pub x: Vec<[f64; 3]>,
}

impl ContactTets {
    /// Number of tets.
    pub fn len(&self) -> usize {
        self.gid.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.gid.is_empty()
    }

    /// Corners of tet `t`.
    pub fn corners(&self, t: usize) -> [[f64; 3]; 4] {
        self.tets[t].map(|n| self.x[n as usize])
    }

    /// Bit i set when node i of tet `t` lies on its body's boundary.
    pub fn node_bits(&self, t: usize) -> u8 {
        self.tets[t].iter().enumerate().fold(0, |m, (i, &n)| {
            m | (u8::from(self.node_boundary[n as usize]) << i)
        })
    }
}

/// Own and ghost tets seen as one list of handles: own tets first.
pub struct OwnAndGhosts<'a> {
    /// This rank's tets.
    pub own: &'a ContactTets,
    /// Other ranks' tets within reach.
    pub ghosts: &'a ContactTets,
}

impl OwnAndGhosts<'_> {
    /// The tets and the index in them of handle `h`.
    pub fn locate(&self, h: u32) -> (&ContactTets, usize) {
        self.at(h)
    }

    fn at(&self, h: u32) -> (&ContactTets, usize) {
        let n = self.own.len() as u32;
        if h < n {
            (self.own, h as usize)
        } else {
            (self.ghosts, (h - n) as usize)
        }
    }

    /// Number of handles.
    pub fn len(&self) -> usize {
        self.own.len() + self.ghosts.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Corners of tet `h`.
    pub fn corners(&self, h: u32) -> [[f64; 3]; 4] {
        let (s, t) = self.at(h);
        s.corners(t)
    }

    /// Global id of tet `h`.
    pub fn gid(&self, h: u32) -> u32 {
        let (s, t) = self.at(h);
        s.gid[t]
    }

    /// The narrow phase's view of tet `h`.
    pub fn faces(&self, h: u32) -> TetFaces {
        let (s, t) = self.at(h);
        TetFaces {
            id: s.gid[t],
            mask: s.mask[t],
            bits: s.node_bits(t),
        }
    }

    /// The tets grouped by body for the search; own tets are searched from.
    pub fn body_tets(&self, held: impl Fn(u32) -> bool, fixed: impl Fn(u32) -> bool) -> BodyTets {
        BodyTets::new(
            self.len() as u32,
            |h| {
                let (s, t) = self.at(h);
                TetRole {
                    body: s.body[t],
                    boundary: s.mask[t] != 0,
                    owned: h < self.own.len() as u32,
                }
            },
            held,
            fixed,
        )
    }

    /// The assembly's view of a pair of tets `a` and `b` labelled as
    /// `pair` (target = the lower global id).
    pub fn dofs(&self, a: u32, b: u32) -> PairDofs {
        let (t, c) = if self.gid(a) < self.gid(b) {
            (a, b)
        } else {
            (b, a)
        };
        let mut d = PairDofs::default();
        for (k, h) in [t, c].into_iter().enumerate() {
            let (s, i) = self.at(h);
            for j in 0..4 {
                d.petsc[4 * k + j] = s.node_petsc[s.tets[i][j] as usize];
            }
            d.materials[k] = s.material[i];
            d.bodies[k] = s.body[i];
        }
        d
    }

    /// The thermal contact pairs among `candidates` (handles) at the
    /// current corners, each with its dofs, sorted by (target, contactor);
    /// with `penetration`, each pair's mean penetration too.
    pub fn contact_pairs(
        &self,
        candidates: &[Candidate],
        penetration: bool,
    ) -> Vec<(ContactPair, PairDofs)> {
        // The search lists each searching tet's candidates together: its
        // shape is made once for them.
        let mut last: Option<(u32, TetShape)> = None;
        let mut out: Vec<(ContactPair, PairDofs)> = candidates
            .iter()
            .filter_map(|c| {
                let sa = match last {
                    Some((h, s)) if h == c.a => s,
                    _ => {
                        let s = TetShape::new(self.corners(c.a));
                        last = Some((c.a, s));
                        s
                    }
                };
                let sb = TetShape::new(self.corners(c.b));
                let (ca, cb) = (&sa.corners, &sb.corners);
                let p = tet_shapes_contact((self.faces(c.a), &sa), (self.faces(c.b), &sb))?;
                let mut d = self.dofs(c.a, c.b);
                if penetration {
                    d.penetration = super::penetration(ca, cb, p.area());
                }
                Some((p, d))
            })
            .collect();
        out.sort_by_key(|(p, _)| (p.target, p.contactor));
        out
    }

    /// Issue 20: the near-field gap links among `candidates` at the current
    /// corners. Each boundary face of a searching tet (`a`) is linked at
    /// most once per other body, to the facing boundary face its normal
    /// ray meets first within `pinball` ([`super::gap::face_gap`]); the
    /// search finds every pair of two bodies from one side, on the rank
    /// that owns the searching tet, so each face is linked once over the
    /// ranks. Sorted by (tet, face, body).
    pub fn gap_links(
        &self,
        candidates: &[Candidate],
        range: super::gap::GapRange,
    ) -> Vec<super::gap::GapLink> {
        use super::gap::{better, tet_links, GapLink};
        let mut best: std::collections::BTreeMap<(u32, u8, u32), GapLink> = Default::default();
        for c in candidates.iter().filter(|c| c.b_boundary) {
            let ((sa, ia), (sb, ib)) = (self.at(c.a), self.at(c.b));
            if sa.body[ia] == sb.body[ib] {
                continue;
            }
            let rows = |s: &ContactTets, i: usize, f: u8| {
                crate::mesh::LOCAL_FACES[f as usize].map(|k| s.node_petsc[s.tets[i][k] as usize])
            };
            let (ca, cb) = (sa.corners(ia), sb.corners(ib));
            for (fa, fb, gap, beta, area) in tet_links(&ca, sa.mask[ia], &cb, sb.mask[ib], range) {
                let l = GapLink {
                    rows_a: rows(sa, ia, fa),
                    rows_b: rows(sb, ib, fb),
                    beta,
                    area,
                    gap,
                    materials: [sa.material[ia], sb.material[ib]],
                    tets: [sa.gid[ia], sb.gid[ib]],
                    faces: [fa, fb],
                };
                let key = (sa.gid[ia], fa, sb.body[ib]);
                if best.get(&key).is_none_or(|b| better(&l, b)) {
                    best.insert(key, l);
                }
            }
        }
        best.into_values().collect()
    }

    /// The candidates of a search over own and ghost tets.
    pub fn search(
        &self,
        search: &mut ContactSearch,
        tets: &BodyTets,
        opts: SearchOptions,
    ) -> Vec<Candidate> {
        search.find(tets, |h| self.corners(h), |h| self.gid(h), opts)
    }
}
