//! Ghost copies of other ranks' bodies for the contact search: each rank
//! holds the tets of the bodies (or of the pieces of split bodies) it owns;
//! before a search it receives copies of the tets of other ranks' pieces
//! whose boxes come within the search margin of its own pieces, from their
//! owners, and nothing else. Neighbour exchange, not an all-gather: the
//! only global data is one box per rank.
//!
//! Collective over all ranks (four personalised exchanges, the first of
//! one box per rank).

use std::collections::HashMap;

use mpi::traits::*;

use super::exchange::{all_gather, all_to_all};
use crate::contact::ContactTets;

type Aabb = ([f64; 3], [f64; 3]);

fn empty_box() -> Aabb {
    ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3])
}

fn grow(b: &mut Aabb, p: [f64; 3]) {
    for (d, &x) in p.iter().enumerate() {
        b.0[d] = b.0[d].min(x);
        b.1[d] = b.1[d].max(x);
    }
}

fn union(b: &mut Aabb, o: &Aabb) {
    grow(b, o.0);
    grow(b, o.1);
}

fn overlap(a: &Aabb, b: &Aabb, g: f64) -> bool {
    (0..3).all(|d| a.0[d] - g <= b.1[d] && b.0[d] <= a.1[d] + g)
}

/// One body's tets on this rank: the indices of its tets and of their
/// nodes in the rank's [`ContactTets`], and their box.
struct Piece {
    body: u32,
    tets: Vec<u32>,
    nodes: Vec<u32>,
    bounds: Aabb,
}

/// The pieces of a rank's tets, one per body: grouped once, boxed at each
/// exchange from the current positions.
#[derive(Default)]
pub struct Pieces {
    pieces: Vec<Piece>,
}

impl Pieces {
    /// Group the tets of `own` by body.
    pub fn new(own: &ContactTets) -> Pieces {
        let mut by_body: HashMap<u32, Vec<u32>> = HashMap::new();
        for (t, &b) in own.body.iter().enumerate() {
            by_body.entry(b).or_default().push(t as u32);
        }
        let mut pieces: Vec<Piece> = by_body
            .into_iter()
            .map(|(body, tets)| {
                let mut nodes: Vec<u32> = tets.iter().flat_map(|&t| own.tets[t as usize]).collect();
                nodes.sort_unstable();
                nodes.dedup();
                Piece {
                    body,
                    tets,
                    nodes,
                    bounds: empty_box(),
                }
            })
            .collect();
        pieces.sort_by_key(|p| p.body);
        Pieces { pieces }
    }

    /// Box every piece at the positions of `own`.
    fn update(&mut self, own: &ContactTets) {
        for p in &mut self.pieces {
            let mut b = empty_box();
            for &n in &p.nodes {
                grow(&mut b, own.x[n as usize]);
            }
            p.bounds = b;
        }
    }
}

fn box_f64(b: &Aabb) -> [f64; 6] {
    [b.0[0], b.0[1], b.0[2], b.1[0], b.1[1], b.1[2]]
}

fn f64_box(v: &[f64]) -> Aabb {
    ([v[0], v[1], v[2]], [v[3], v[4], v[5]])
}

/// Collective. The tets of other ranks' pieces that come within `margin`
/// of this rank's pieces of `own`: boundary tets only, or every tet with
/// `interior` (the thermal contact also pairs a boundary face with
/// another body's interior tets). Each rank receives a piece's tets whose
/// boxes come within the margin of the box of its own pieces near it.
/// Nodes are listed once each, by ascending global id. The bodies
/// `self_bodies` (ascending: split bodies that search themselves) are
/// also brought near this rank's own pieces of them.
pub fn exchange_ghosts<C: Communicator>(
    comm: &C,
    own: &ContactTets,
    pieces: &mut Pieces,
    margin: f64,
    interior: bool,
    self_bodies: &[u32],
) -> ContactTets {
    let size = comm.size() as usize;
    let me = comm.rank() as usize;
    pieces.update(own);
    let mine = &pieces.pieces;
    // 1. One box per rank.
    let mut rank_box = empty_box();
    for p in mine {
        union(&mut rank_box, &p.bounds);
    }
    let boxes: Vec<f64> = all_gather(comm, &box_f64(&rank_box));
    // 2. Piece boxes to the ranks whose box comes within the margin.
    let mut send: Vec<Vec<f64>> = vec![Vec::new(); size];
    for (r, rb) in boxes.chunks_exact(6).enumerate() {
        if r == me || !overlap(&f64_box(rb), &rank_box, margin) {
            continue;
        }
        let rb = f64_box(rb);
        for p in mine {
            if overlap(&p.bounds, &rb, margin) {
                send[r].push(f64::from(p.body));
                send[r].extend_from_slice(&box_f64(&p.bounds));
            }
        }
    }
    let offered = all_to_all(comm, send);
    // 3. Requests for the offered pieces near own pieces of other bodies
    //    (or of the same body, for `self_bodies`),
    //    each with the box of those own pieces (the owner sends only the
    //    tets near it).
    let mut requests: Vec<Vec<f64>> = vec![Vec::new(); size];
    for (r, list) in offered.iter().enumerate() {
        for rec in list.chunks_exact(7) {
            let (body, qb) = (rec[0] as u32, f64_box(&rec[1..]));
            let mut near = empty_box();
            let itself = self_bodies.binary_search(&body).is_ok();
            for p in mine.iter().filter(|p| p.body != body || itself) {
                if overlap(&p.bounds, &qb, margin) {
                    union(&mut near, &p.bounds);
                }
            }
            if near.0[0] <= near.1[0] {
                requests[r].push(f64::from(body));
                requests[r].extend_from_slice(&box_f64(&near));
            }
        }
    }
    let asked = all_to_all(comm, requests);
    // 4. The tets asked for, each piece's nodes once: per piece a header
    //    (nodes, tets), its nodes (gid, owner, PETSc number, boundary,
    //    x, y, z), then its tets (gid, body, material, mask, volume, and
    //    four indices into the piece's nodes).
    const NODE: usize = 7;
    const TET: usize = 9;
    let mut data: Vec<Vec<f64>> = vec![Vec::new(); size];
    let mut local_of: Vec<u32> = vec![u32::MAX; own.x.len()];
    let mut picked: Vec<usize> = Vec::new();
    let mut piece_nodes: Vec<u32> = Vec::new();
    for (r, list) in asked.iter().enumerate() {
        for rec in list.chunks_exact(7) {
            let (body, near) = (rec[0] as u32, f64_box(&rec[1..]));
            let Ok(i) = mine.binary_search_by_key(&body, |p| p.body) else {
                continue;
            };
            picked.clear();
            piece_nodes.clear();
            for &t in &mine[i].tets {
                let t = t as usize;
                if !interior && own.mask[t] == 0 {
                    continue;
                }
                let mut tb = empty_box();
                for p in own.corners(t) {
                    grow(&mut tb, p);
                }
                if !overlap(&tb, &near, margin) {
                    continue;
                }
                picked.push(t);
                for &n in &own.tets[t] {
                    if local_of[n as usize] == u32::MAX {
                        local_of[n as usize] = piece_nodes.len() as u32;
                        piece_nodes.push(n);
                    }
                }
            }
            if picked.is_empty() {
                continue;
            }
            let out = &mut data[r];
            out.reserve(2 + NODE * piece_nodes.len() + TET * picked.len());
            out.extend_from_slice(&[piece_nodes.len() as f64, picked.len() as f64]);
            for &n in &piece_nodes {
                let n = n as usize;
                let x = own.x[n];
                out.extend_from_slice(&[
                    f64::from(own.node_gid[n]),
                    f64::from(own.node_owner[n]),
                    f64::from(own.node_petsc[n]),
                    f64::from(u8::from(own.node_boundary[n])),
                    x[0],
                    x[1],
                    x[2],
                ]);
            }
            for &t in &picked {
                out.extend_from_slice(&[
                    f64::from(own.gid[t]),
                    f64::from(own.body[t]),
                    f64::from(own.material[t]),
                    f64::from(own.mask[t]),
                    own.volume0[t],
                ]);
                out.extend(own.tets[t].iter().map(|&n| f64::from(local_of[n as usize])));
            }
            for &n in &piece_nodes {
                local_of[n as usize] = u32::MAX;
            }
        }
    }
    drop(local_of);
    let received = all_to_all(comm, data);

    // Assemble, each node once, by ascending global id; a node that came
    // in several pieces keeps its first arrival. Tets refer to arrivals
    // until the nodes are ordered.
    let mut nodes: Vec<[f64; NODE]> = Vec::new();
    let mut g = ContactTets::default();
    let mut tet_nodes: Vec<[u32; 4]> = Vec::new();
    for list in &received {
        let mut at = 0;
        while at < list.len() {
            let (nn, nt) = (list[at] as usize, list[at + 1] as usize);
            at += 2;
            let base = nodes.len() as u32;
            nodes.extend(
                list[at..at + NODE * nn]
                    .chunks_exact(NODE)
                    .map(|n| <[f64; NODE]>::try_from(n).expect("seven values")),
            );
            at += NODE * nn;
            for rec in list[at..at + TET * nt].chunks_exact(TET) {
                g.gid.push(rec[0] as u32);
                g.body.push(rec[1] as u32);
                g.material.push(rec[2] as u32);
                g.mask.push(rec[3] as u8);
                g.volume0.push(rec[4]);
                tet_nodes.push(std::array::from_fn(|k| base + rec[5 + k] as u32));
            }
            at += TET * nt;
        }
    }
    drop(received);
    // (gid, arrival) keys are distinct: sorted, they give the first arrival of each gid first.
    let mut keys: Vec<(u32, u32)> = nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (n[0] as u32, i as u32))
        .collect();
    keys.sort_unstable();
    let mut index_of = vec![0u32; nodes.len()];
    for &(gid, i) in &keys {
        if g.node_gid.last() != Some(&gid) {
            let n = &nodes[i as usize];
            g.node_gid.push(gid);
            g.node_owner.push(n[1] as u32);
            g.node_petsc.push(n[2] as u32);
            g.node_boundary.push(n[3] != 0.0);
            g.x.push([n[4], n[5], n[6]]);
        }
        index_of[i as usize] = (g.node_gid.len() - 1) as u32;
    }
    g.tets = tet_nodes
        .iter()
        .map(|t| t.map(|a| index_of[a as usize]))
        .collect();
    g
}
