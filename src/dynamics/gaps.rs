//! Near-field gap links in a coupled run (issue 20, seed 001 sec 7.1.1):
//! found among the penalty contact's candidates (whose margin covers
//! twice the pinball distance when gaps are on), from the side of the
//! body that finds the pair ([`finds_pair`], as the thermal search does),
//! and reduced over the ranks to one link per searching face and other
//! body, the nearest, so the links do not depend on the number of ranks.

use std::collections::BTreeMap;

use mpi::topology::{Communicator, SimpleCommunicator};

use super::ExplicitDomain;
use crate::contact::finds_pair;
use crate::contact::gap::{better, tet_links, GapLink, GapRange};
use crate::mesh::LOCAL_FACES;
use crate::parallel::exchange::all_to_all;

/// Values per link on the wire: its fields and the other body.
const WIDTH: usize = 18;

fn pack(l: &GapLink, body_b: u32, out: &mut Vec<f64>) {
    out.extend(l.rows_a.map(f64::from));
    out.extend(l.rows_b.map(f64::from));
    out.extend(l.beta);
    out.extend([l.area, l.gap]);
    out.extend(l.materials.map(f64::from));
    out.extend(l.tets.map(f64::from));
    out.extend(l.faces.map(f64::from));
    out.push(f64::from(body_b));
}

fn unpack(r: &[f64]) -> (GapLink, u32) {
    let u = |k: usize| r[k] as u32;
    let l = GapLink {
        rows_a: [u(0), u(1), u(2)],
        rows_b: [u(3), u(4), u(5)],
        beta: [r[6], r[7], r[8]],
        area: r[9],
        gap: r[10],
        materials: [u(11), u(12)],
        tets: [u(13), u(14)],
        faces: [r[15] as u8, r[16] as u8],
    };
    (l, u(17))
}

impl ExplicitDomain {
    /// Set this rank's share of the friction's work so far (J).
    pub fn set_friction_work(&mut self, w: f64) {
        self.friction_work = w;
    }

    /// This rank's share of the friction's work so far (J).
    pub fn friction_work_share(&self) -> f64 {
        self.friction_work
    }

    /// Make the candidate search margin at least `m` (renewing the
    /// candidates at the next detection).
    pub fn widen_margin(&mut self, m: f64) {
        if m > self.margin_min {
            self.margin_min = m;
            self.margin = self.margin.max(m);
            self.redetect = true;
        }
    }

    /// Collective. The gap links at the current positions: each rank's
    /// candidates give theirs, sent to the rank `tet mod ranks` of the
    /// searching tet, which keeps the nearest per (tet, face, other body).
    pub fn gap_links(&self, comm: &SimpleCommunicator, range: GapRange) -> Vec<GapLink> {
        let size = comm.size() as usize;
        let mut send: Vec<Vec<f64>> = vec![Vec::new(); size];
        let corners = |t: &[u32; 4]| {
            t.map(|l| {
                let p = &self.x[l as usize];
                [p.x, p.y, p.z]
            })
        };
        for c in &self.candidates {
            let (a, b) = (c.ta as usize, c.tb as usize);
            let (ia, ib) = (&self.pair_info[a], &self.pair_info[b]);
            if ia.body == ib.body || ia.mask == 0 || ib.mask == 0 {
                continue;
            }
            let held = |body: u32| self.body_held[body as usize];
            let (a, b) = if finds_pair(ia.body, held(ia.body), ib.body, held(ib.body)) {
                (a, b)
            } else {
                (b, a)
            };
            let (ia, ib) = (&self.pair_info[a], &self.pair_info[b]);
            let (ta, tb) = (&self.pair_tets[a], &self.pair_tets[b]);
            let rows = |t: &[u32; 4], f: u8| {
                LOCAL_FACES[f as usize].map(|k| self.node_petsc[t[k] as usize])
            };
            for (fa, fb, gap, beta, area) in
                tet_links(&corners(ta), ia.mask, &corners(tb), ib.mask, range)
            {
                let l = GapLink {
                    rows_a: rows(ta, fa),
                    rows_b: rows(tb, fb),
                    beta,
                    area,
                    gap,
                    materials: [ia.material, ib.material],
                    tets: [ia.gid, ib.gid],
                    faces: [fa, fb],
                };
                pack(&l, ib.body, &mut send[ia.gid as usize % size]);
            }
        }
        let got = all_to_all(comm, send);
        let mut best: BTreeMap<(u32, u8, u32), GapLink> = BTreeMap::new();
        for r in got.iter().flat_map(|v| v.chunks_exact(WIDTH)) {
            let (l, body_b) = unpack(r);
            let key = (l.tets[0], l.faces[0], body_b);
            if best.get(&key).is_none_or(|b| better(&l, b)) {
                best.insert(key, l);
            }
        }
        best.into_values().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_link_travels_whole() {
        let l = GapLink {
            rows_a: [1, 2, 3],
            rows_b: [40, 50, 60],
            beta: [0.2, 0.3, 0.5],
            area: 1e-4,
            gap: 2e-4,
            materials: [0, 1],
            tets: [7, 900],
            faces: [3, 1],
        };
        let mut v = Vec::new();
        pack(&l, 12, &mut v);
        assert_eq!(v.len(), WIDTH);
        assert_eq!(unpack(&v), (l, 12));
    }
}
