//! Particle packs (seed 000 sec 6): where the copies of one particle
//! template go above a container for a deposition run (a rigid motion per
//! copy; the meshes are made by the ranks that hold them). No MPI or PETSc.
//!
//! Checks made before any work, each naming the scenario entry: the
//! template is a closed volume, the container is wide enough for one
//! particle and holds `count` particles at the largest solid fraction
//! `max_fraction`, and explicitly given positions do not overlap.

use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use crate::geometry::placement::{
    centroid_and_radius, column_sites, drop_sites, random_rotations, Column,
};
use crate::geometry::tet_tet_intersection;
use crate::mesh::TetMesh;
use crate::model::Motion;
use crate::scenario::{MeshSpec, PackSpec, Placement as PlacementKind};

/// Where a particle goes: its centroid and its rotation.
type Placement = (Vector3<f64>, Matrix3<f64>);

/// A container's interior, from its scenario entry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContainerInterior {
    /// Centre of the floor's top face.
    pub floor: [f64; 3],
    /// Inner radius.
    pub radius: f64,
    /// Inner height.
    pub height: f64,
}

impl ContainerInterior {
    /// From a `container` mesh entry and the entry's translation.
    pub fn from_spec(mesh: &MeshSpec, translate: Option<[f64; 3]>) -> Option<Self> {
        match mesh {
            MeshSpec::Container {
                center,
                inner_radius,
                height,
                ..
            } => {
                let t = translate.unwrap_or([0.0; 3]);
                Some(ContainerInterior {
                    floor: [center[0] + t[0], center[1] + t[1], center[2] + t[2]],
                    radius: *inner_radius,
                    height: *height,
                })
            }
            _ => None,
        }
    }
}

/// The placed copies of a particle template: `(name, motion)` per
/// particle. `template` is the particle's mesh as the scenario gives it;
/// each copy is it rotated about its centroid and moved to a site
/// ([`Motion::apply`]). `base` resolves a positions file.
pub fn place(
    name: &str,
    template: &TetMesh,
    spec: &PackSpec,
    container: &ContainerInterior,
    base: &dyn Fn(&str) -> std::path::PathBuf,
) -> Result<Vec<(String, Motion)>, String> {
    template
        .check_closed_volume()
        .map_err(|e| format!("the particle template: {e}"))?;
    let (c, r) = centroid_and_radius(&template.nodes, &template.tets);
    let volume = template.total_volume();
    // Capacity: N V_p ≤ φ_max π R² H.
    let capacity =
        spec.max_fraction * std::f64::consts::PI * container.radius.powi(2) * container.height;
    let need = spec.count as f64 * volume;
    if need > capacity {
        return Err(format!(
            "the container is too small for {} particles: they take {need:.4e} m³ of solid, the \
             container holds {capacity:.4e} m³ at a solid fraction of at most {} \
             (inner radius {} m, height {} m); raise its height or lower pack.count",
            spec.count, spec.max_fraction, container.radius, container.height
        ));
    }
    let placements: Vec<Placement> = match &spec.positions {
        None => {
            let col = Column {
                floor_center: container.floor,
                radius: container.radius,
            };
            let rots = random_rotations(spec.count, spec.seed);
            let sites = match spec.placement {
                PlacementKind::Column => {
                    column_sites(spec.count, r, spec.gap.unwrap_or(0.1 * r), &col)?
                }
                PlacementKind::Drop => {
                    let hull: Vec<[f64; 3]> = template
                        .nodes
                        .iter()
                        .map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
                        .collect();
                    let gap = spec.gap.unwrap_or(0.05 * r);
                    drop_sites(&hull, &rots, gap, spec.trials, spec.seed, &col)?
                }
            };
            sites
                .into_iter()
                .zip(rots)
                .map(|(s, q)| (Vector3::from(s), q.into_inner()))
                .collect()
        }
        Some(file) => {
            let path = base(file);
            let p = read_positions(&path)?;
            if p.len() != spec.count {
                return Err(format!(
                    "{}: {} positions for pack.count = {}",
                    path.display(),
                    p.len(),
                    spec.count
                ));
            }
            p
        }
    };
    let c = Vector3::from(c);
    let copies: Vec<(String, Motion)> = placements
        .iter()
        .enumerate()
        .map(|(i, (site, rot))| {
            let motion = Motion::Place {
                rotation: *rot,
                center: c,
                site: *site,
            };
            (format!("{name}_{i}"), motion)
        })
        .collect();
    if spec.positions.is_some() {
        let meshes: Vec<(String, TetMesh)> = copies
            .iter()
            .map(|(n, m)| (n.clone(), moved(template, m)))
            .collect();
        check_no_overlap(&meshes, r)?;
    }
    Ok(copies)
}

/// `template` moved by `motion`.
pub fn moved(template: &TetMesh, motion: &Motion) -> TetMesh {
    let mut m = template.clone();
    for p in m.nodes.iter_mut() {
        *p = motion.apply(*p);
    }
    m
}

/// Particles given as `x, y, z, rx, ry, rz` lines (rotations in degrees
/// about x, then y, then z).
fn read_positions(path: &Path) -> Result<Vec<Placement>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read the positions file {}: {e}", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let v: Result<Vec<f64>, _> = line
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(str::parse::<f64>)
            .collect();
        match v {
            Ok(v) if v.len() == 6 && v.iter().all(|x| x.is_finite()) => {
                let rot = crate::geometry::transform::rotation_xyz_degrees([v[3], v[4], v[5]]);
                out.push((Vector3::new(v[0], v[1], v[2]), rot));
            }
            _ => {
                return Err(format!(
                    "{}:{}: expected six finite numbers `x, y, z, rx, ry, rz`, got `{line}`",
                    path.display(),
                    i + 1
                ))
            }
        }
    }
    Ok(out)
}

/// Fail if two particles' volumes overlap (their bounding spheres of
/// radius `r` about the centroids meet and some pair of their tets
/// intersects with a positive volume).
fn check_no_overlap(copies: &[(String, TetMesh)], r: f64) -> Result<(), String> {
    let cents: Vec<[f64; 3]> = copies
        .iter()
        .map(|(_, m)| centroid_and_radius(&m.nodes, &m.tets).0)
        .collect();
    for i in 0..copies.len() {
        for j in 0..i {
            let d = Vector3::from(cents[i]) - Vector3::from(cents[j]);
            if d.norm() >= 2.0 * r {
                continue;
            }
            if let Some(v) = overlap_volume(&copies[i].1, &copies[j].1) {
                return Err(format!(
                    "particles `{}` and `{}` overlap at the start (intersection volume {v:.3e} m³): \
                     the positions must leave the particles apart",
                    copies[j].0, copies[i].0
                ));
            }
        }
    }
    Ok(())
}

/// Some positive intersection volume of two meshes, if any.
pub fn overlap_volume(a: &TetMesh, b: &TetMesh) -> Option<f64> {
    let boxes = |m: &TetMesh| -> Vec<([f64; 3], [f64; 3])> {
        (0..m.tets.len())
            .map(|e| crate::geometry::tet_bounds(&m.element_coords(e)))
            .collect()
    };
    let (ba, bb) = (boxes(a), boxes(b));
    for (ea, (la, ha)) in ba.iter().enumerate() {
        for (eb, (lb, hb)) in bb.iter().enumerate() {
            if (0..3).any(|d| la[d] > hb[d] || lb[d] > ha[d]) {
                continue;
            }
            let (xa, xb) = (a.element_coords(ea), b.element_coords(eb));
            let v = tet_tet_intersection(&xa, &xb).volume;
            let tiny = 1e-9 * a.element_volume(ea).min(b.element_volume(eb));
            if v > tiny {
                return Some(v);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::nut::nut_mesh_default;

    fn spec(count: usize) -> PackSpec {
        PackSpec {
            count,
            seed: 3,
            into: "c".into(),
            placement: PlacementKind::Drop,
            trials: 8,
            gap: None,
            max_fraction: 0.64,
            positions: None,
        }
    }

    const BOX: ContainerInterior = ContainerInterior {
        floor: [0.0, 0.0, 0.0],
        radius: 0.225,
        height: 0.6,
    };

    #[test]
    fn placed_nuts_do_not_overlap_and_keep_their_shape() {
        let nut = nut_mesh_default([0.0; 3]).unwrap();
        let mut column = spec(60);
        column.placement = PlacementKind::Column;
        let meshes = |placed: Vec<(String, Motion)>| -> Vec<(String, TetMesh)> {
            placed
                .iter()
                .map(|(n, m)| (n.clone(), moved(&nut, m)))
                .collect()
        };
        let stacked = meshes(place("nut", &nut, &column, &BOX, &|s| s.into()).unwrap());
        for i in 0..8 {
            for j in 0..i {
                assert!(overlap_volume(&stacked[i].1, &stacked[j].1).is_none());
            }
        }
        let copies = meshes(place("nut", &nut, &spec(60), &BOX, &|s| s.into()).unwrap());
        assert_eq!(copies.len(), 60);
        for (_, m) in &copies {
            assert!((m.total_volume() - nut.total_volume()).abs() < 1e-12 * nut.total_volume());
            m.validate().unwrap();
        }
        // Same seed, same placement; another seed, another.
        let again = meshes(place("nut", &nut, &spec(60), &BOX, &|s| s.into()).unwrap());
        assert_eq!(copies, again);
        let mut s2 = spec(60);
        s2.seed = 4;
        let other = meshes(place("nut", &nut, &s2, &BOX, &|s| s.into()).unwrap());
        assert_ne!(copies[0].1.nodes, other[0].1.nodes);
        // Dropped: every pair of the first 20 (they touch within the gap).
        for i in 0..20 {
            for j in 0..i {
                assert!(overlap_volume(&copies[i].1, &copies[j].1).is_none());
            }
        }
    }

    #[test]
    fn a_small_container_is_refused() {
        let nut = nut_mesh_default([0.0; 3]).unwrap();
        let small = ContainerInterior {
            height: 0.02,
            ..BOX
        };
        let e = place("nut", &nut, &spec(2000), &small, &|s| s.into()).unwrap_err();
        assert!(e.contains("too small for 2000 particles"), "{e}");
    }

    #[test]
    fn overlapping_positions_are_refused() {
        let nut = nut_mesh_default([0.0; 3]).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("p.csv");
        std::fs::write(&f, "# x y z rx ry rz\n0,0,0.05,0,0,0\n0.01,0,0.05,0,0,30\n").unwrap();
        let mut s = spec(2);
        s.positions = Some("p.csv".into());
        let e = place("nut", &nut, &s, &BOX, &|p| dir.path().join(p)).unwrap_err();
        assert!(e.contains("`nut_0` and `nut_1` overlap"), "{e}");
        std::fs::write(&f, "0,0,0.05,0,0,0\n0.1,0,0.05\n").unwrap();
        let e = place("nut", &nut, &s, &BOX, &|p| dir.path().join(p)).unwrap_err();
        assert!(e.contains("p.csv:2"), "{e}");
        std::fs::write(&f, "0,0,0.05,0,0,0\n0.1,0,0.05,90,0,0\n").unwrap();
        assert_eq!(
            place("nut", &nut, &s, &BOX, &|p| dir.path().join(p))
                .unwrap()
                .len(),
            2
        );
    }
}
