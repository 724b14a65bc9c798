//! Element partitioning with METIS over the face-adjacency (dual) graph.

use mpi::traits::*;

use crate::mesh::TetMesh;

/// Collective. The part (rank) of every element: METIS on rank 0 over the
/// dual graph of `mesh`, balancing per-element work `weights`, with the
/// element pairs `links(mesh)` (computed on rank 0 only) joined in the
/// graph as well (touching bodies' boundary tets, so a packing is not cut
/// through every contact); broadcast to every rank.
pub fn partition_collective<C: Communicator>(
    comm: &C,
    mesh: &TetMesh,
    weights: Option<&[i32]>,
    links: impl Fn(&TetMesh) -> Vec<(u32, u32)>,
) -> Result<Vec<u32>, String> {
    let size = comm.size() as usize;
    let rank = comm.rank() as usize;
    let mut part: Vec<u32> = vec![0; mesh.tets.len()];
    let mut status: i32 = 0;
    let links = |mesh: &TetMesh| if size > 1 { links(mesh) } else { Vec::new() };
    if rank == 0 {
        match partition_elements_weighted(mesh, size, weights, &links(mesh)) {
            Ok(p) => part = p,
            Err(_) => status = 1,
        }
    }
    comm.process_at_rank(0).broadcast_into(&mut status);
    if status != 0 {
        // Recompute on every rank to get the same message everywhere.
        return Err(
            partition_elements_weighted(mesh, size, weights, &links(mesh))
                .err()
                .unwrap_or_else(|| "partitioning failed".into()),
        );
    }
    if size > 1 {
        comm.process_at_rank(0).broadcast_into(&mut part[..]);
    }
    Ok(part)
}

/// The dual graph in CSR form: elements are adjacent when they share a face.
pub fn dual_graph(mesh: &TetMesh) -> (Vec<i32>, Vec<i32>) {
    dual_graph_with(mesh, &[])
}

/// The dual graph plus `extra` edges (element pairs, e.g. boundary tets of
/// touching bodies), each counted once.
pub fn dual_graph_with(mesh: &TetMesh, extra: &[(u32, u32)]) -> (Vec<i32>, Vec<i32>) {
    let ne = mesh.tets.len();
    let mut faces: Vec<([u32; 3], u32)> = Vec::with_capacity(4 * ne);
    for (e, t) in mesh.tets.iter().enumerate() {
        for skip in 0..4 {
            let mut f = [0u32; 3];
            let mut k = 0;
            for (i, &n) in t.iter().enumerate() {
                if i != skip {
                    f[k] = n;
                    k += 1;
                }
            }
            f.sort_unstable();
            faces.push((f, e as u32));
        }
    }
    faces.sort_unstable();
    let mut deg = vec![0i32; ne + 1];
    let mut pairs = Vec::with_capacity(2 * ne);
    let mut i = 0;
    while i + 1 < faces.len() {
        if faces[i].0 == faces[i + 1].0 {
            let (a, b) = (faces[i].1, faces[i + 1].1);
            pairs.push((a, b));
            deg[a as usize + 1] += 1;
            deg[b as usize + 1] += 1;
            i += 2;
        } else {
            i += 1;
        }
    }
    for &(a, b) in extra {
        if a != b {
            pairs.push((a, b));
            deg[a as usize + 1] += 1;
            deg[b as usize + 1] += 1;
        }
    }
    for e in 0..ne {
        deg[e + 1] += deg[e];
    }
    let xadj = deg;
    let mut fill: Vec<i32> = xadj[..ne].to_vec();
    let mut adj = vec![0i32; xadj[ne] as usize];
    for (a, b) in pairs {
        adj[fill[a as usize] as usize] = b as i32;
        fill[a as usize] += 1;
        adj[fill[b as usize] as usize] = a as i32;
        fill[b as usize] += 1;
    }
    (xadj, adj)
}

/// Partition the elements into `nparts` parts with METIS k-way (element
/// count balanced, face cut minimised). Deterministic for a given mesh.
pub fn partition_elements(mesh: &TetMesh, nparts: usize) -> Result<Vec<u32>, String> {
    partition_elements_weighted(mesh, nparts, None, &[])
}

/// As [`partition_elements`], balancing the sum of per-element `weights`
/// (work estimates) instead of the element count, and counting the
/// `links` (pairs of elements of touching bodies) in the cut like shared
/// faces, so that a packing is cut between clusters of particles rather
/// than through every contact.
pub fn partition_elements_weighted(
    mesh: &TetMesh,
    nparts: usize,
    weights: Option<&[i32]>,
    links: &[(u32, u32)],
) -> Result<Vec<u32>, String> {
    let ne = mesh.tets.len();
    if nparts <= 1 || ne == 0 {
        return Ok(vec![0; ne]);
    }
    if ne < nparts {
        return Err(format!("{ne} elements cannot be split over {nparts} ranks"));
    }
    let (xadj, adj) = dual_graph_with(mesh, links);
    let mut part = vec![0i32; ne];
    let mut graph = metis::Graph::new(1, nparts as i32, &xadj, &adj)
        .map_err(|e| format!("METIS graph: {e}"))?;
    if let Some(w) = weights {
        if w.len() != ne {
            return Err(format!("{} element weights for {ne} elements", w.len()));
        }
        graph = graph.set_vwgt(w);
    }
    graph
        .set_option(metis::option::Seed(1))
        .part_kway(&mut part)
        .map_err(|e| format!("METIS_PartGraphKway: {e:?}"))?;
    Ok(part.into_iter().map(|p| p as u32).collect())
}
