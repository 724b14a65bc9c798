//! A body's element set made particles (issue 21, seed 002): at load the
//! set's elements leave the body's FE mesh and become a bonded sphere
//! lattice ([`crate::mesh::particle_region`]) linked to the remaining
//! elements by ghost particles. The lattice is part of the body's source
//! mesh, like a jointed body's joints (every rank reads it, as the source
//! mesh); a rank makes the spheres, bonds and links of its part of the
//! body (`parallel::spheres`).

use super::{BodySource, Model};
use crate::mesh::particle_region::{particle_region, ParticleRegion};
use crate::mesh::without::without_elements;
use crate::mesh::TetMesh;
use crate::scenario::BodySpec;

/// The particles of a source mesh: the lattice and its links (element
/// numbers of the source mesh, which no longer has the set), and the
/// particles' material (index into the model's materials).
#[derive(Debug, Clone)]
pub struct SourceParticles {
    pub region: ParticleRegion,
    pub material: u32,
    /// The spheres (ascending) of each set of the mesh as given that
    /// holds some: an element set's, those whose centre lies in one of its
    /// elements; a node set's, those whose element has all four nodes in
    /// it (what a `thermal.initial` on the set gives them).
    pub sphere_sets: std::collections::BTreeMap<String, Vec<u32>>,
}

/// The spheres of each element and node set of `m` ([`SourceParticles::sphere_sets`]).
fn sphere_sets(
    m: &TetMesh,
    region: &ParticleRegion,
) -> std::collections::BTreeMap<String, Vec<u32>> {
    let mut out = std::collections::BTreeMap::new();
    let mut mark = vec![false; m.tets.len()];
    for (name, elems) in &m.elem_sets {
        mark.iter_mut().for_each(|x| *x = false);
        elems.iter().for_each(|&e| mark[e as usize] = true);
        let s: Vec<u32> = (0..region.centres.len() as u32)
            .filter(|&k| mark[region.source_elem[k as usize] as usize])
            .collect();
        if !s.is_empty() {
            out.insert(name.clone(), s);
        }
    }
    let mut node = vec![false; m.nodes.len()];
    for (name, nodes) in &m.node_sets {
        node.iter_mut().for_each(|x| *x = false);
        nodes.iter().for_each(|&n| node[n as usize] = true);
        let s: Vec<u32> = (0..region.centres.len() as u32)
            .filter(|&k| {
                let e = region.source_elem[k as usize] as usize;
                m.tets[e].iter().all(|&n| node[n as usize])
            })
            .collect();
        if !s.is_empty() {
            out.entry(name.clone()).or_insert(s);
        }
    }
    out
}

/// The body and set a `thermal.initial` names (`<body>.<set>` or `<set>`,
/// as [`super::bcs::resolve`]): a node, face or element set of a body's
/// mesh, or a set of the mesh as given that holds some of its particles
/// (`sphere_sets`); its nodes and spheres together not empty. `source(k)`
/// is body k's source mesh, if it has one.
pub(super) fn initial_target<'a>(
    name: &str,
    names: &[String],
    source: impl Fn(usize) -> Option<&'a super::bodies::SourceMesh>,
) -> Result<super::bcs::SetTarget, String> {
    let nodes = |k: usize, set: &str| {
        source(k).map_or(0, |s| super::bcs::initial_nodes(&s.mesh, set).len())
    };
    let spheres = |k: usize, set: &str| {
        let p = source(k).and_then(|s| s.particles.as_ref());
        p.and_then(|p| p.sphere_sets.get(set)).map_or(0, Vec::len)
    };
    let sets_of = |k: usize| -> Vec<String> {
        let Some(s) = source(k) else {
            return Vec::new();
        };
        let m = &s.mesh;
        let mut v: Vec<String> = (m.node_sets.keys().chain(m.face_sets.keys()))
            .chain(m.elem_sets.keys())
            .chain(s.particles.iter().flat_map(|p| p.sphere_sets.keys()))
            .cloned()
            .collect();
        v.sort();
        v.dedup();
        v
    };
    let has = |k: usize, set: &str| {
        source(k).is_some_and(|s| {
            let m = &s.mesh;
            m.node_sets.contains_key(set)
                || m.face_sets.contains_key(set)
                || m.elem_sets.contains_key(set)
                || spheres(k, set) > 0
        })
    };
    let t = super::bcs::resolve(name, names, sets_of, has)?;
    let k = t.body as usize;
    if nodes(k, &t.set) + spheres(k, &t.set) == 0 {
        return Err(format!("set `{}.{}` is empty", names[k], t.set));
    }
    Ok(t)
}

/// The body `b`'s mesh `m` (element materials `material`, Hex8 `hexes`
/// if any) without the element set of its `particles` key, and the
/// particles; unchanged without the key. A Hex8 body's set must be whole
/// hexes; its remaining hexes are numbered again with their tets (the
/// links attach to their tets, `mesh::particle_region`). Errors name the
/// body and the key.
#[allow(clippy::type_complexity)]
pub(super) fn split_off(
    b: &BodySpec,
    m: TetMesh,
    material: Vec<u32>,
    hexes: Option<Vec<[u32; 8]>>,
) -> Result<
    (
        TetMesh,
        Vec<u32>,
        Option<SourceParticles>,
        Option<Vec<[u32; 8]>>,
    ),
    String,
> {
    let Some(p) = &b.particles else {
        return Ok((m, material, None, hexes));
    };
    let elems = super::bodies::elements_of(&m, &p.set, &b.name, "particles.set")?;
    let mut in_set = vec![false; m.tets.len()];
    elems.iter().for_each(|&e| in_set[e as usize] = true);
    if hexes.is_some() {
        if let Some(h) = (0..m.tets.len() / 6).find(|&h| {
            let s = &in_set[6 * h..6 * h + 6];
            s.iter().any(|&x| x != s[0])
        }) {
            return Err(format!(
                "body `{}`: particles.set: `{}` cuts Hex8 element {h} (it holds some of its six \
                 tets); make the set whole hexes (a box whose faces lie on element faces)",
                b.name, p.set
            ));
        }
    }
    if elems.len() == m.tets.len() {
        return Err(format!(
            "body `{}`: particles.set: `{}` is every element of the body; \
             the body needs finite elements beside its particles",
            b.name, p.set
        ));
    }
    let mat = material[elems[0] as usize];
    if elems.iter().any(|&e| material[e as usize] != mat) {
        return Err(format!(
            "body `{}`: particles.set: the elements of `{}` have more than one material (regions)",
            b.name, p.set
        ));
    }
    let (fe, index) = without_elements(&m, &in_set);
    // The remaining hexes: hex node k is a corner of one of its tets,
    // which keep their corners' order in the new mesh.
    let hexes = hexes.map(|hs| {
        hs.iter()
            .enumerate()
            .filter(|&(h, _)| !in_set[6 * h])
            .map(|(h, hex)| {
                hex.map(|n| {
                    (0..24)
                        .find_map(|k| {
                            let (t, c) = (6 * h + k / 4, k % 4);
                            (m.tets[t][c] == n).then(|| fe.tets[index[t] as usize][c])
                        })
                        .expect("each node of a hex is a corner of one of its tets")
                })
            })
            .collect()
    });
    let region = particle_region(&m, &p.set, &in_set, &index, p.radius)
        .map_err(|e| format!("body `{}`: particles: {e}", b.name))?;
    let sphere_sets = sphere_sets(&m, &region);
    if region.links.is_empty() {
        return Err(format!(
            "body `{}`: particles.set: no sphere of `{}` borders the body's finite elements",
            b.name, p.set
        ));
    }
    let material = (0..m.tets.len())
        .filter(|&e| !in_set[e])
        .map(|e| material[e])
        .collect();
    Ok((
        fe,
        material,
        Some(SourceParticles {
            region,
            material: mat,
            sphere_sets,
        }),
        hexes,
    ))
}

impl Model {
    /// Per body, the global number of its first particle (particles
    /// numbered body by body, each body's in its lattice's order), and the
    /// total: O(bodies), the same on every rank.
    pub fn particle_offsets(&self) -> (Vec<u64>, u64) {
        let mut next = 0u64;
        let offsets = self
            .bodies
            .iter()
            .map(|b| {
                let at = next;
                next += self
                    .body_particles(b)
                    .map_or(0, |p| p.region.centres.len() as u64);
                at
            })
            .collect();
        (offsets, next)
    }

    /// The particles of body `b`, if it has any.
    pub fn body_particles(&self, b: &super::Body) -> Option<&SourceParticles> {
        match b.source {
            BodySource::Mesh { mesh, .. } => self.meshes[mesh as usize].particles.as_ref(),
            BodySource::Saved { .. } => None,
        }
    }

    /// Whether any body has particles.
    pub fn has_particles(&self) -> bool {
        self.meshes.iter().any(|m| m.particles.is_some())
    }
}
