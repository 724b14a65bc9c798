//! A body's own mesh as its scenario entry describes it: generated or
//! read from Gmsh, Tet4 or (issue 21) Hex8 split into tets.

use crate::mesh::{self, MeshError, TetMesh};
use crate::scenario::{ElementKind, LoadedScenario, MeshSpec};

/// The hexes of a Hex8 mesh: hex `h` is tets `6 h .. 6 h + 6`
/// (`mesh::hex_tets`); `None` for a Tet4 mesh.
type Hexes = Option<Vec<[u32; 8]>>;

/// The mesh of `spec` (not a checkpoint), and its hexes if Hex8.
pub(super) fn body_mesh(
    spec: &MeshSpec,
    sc: &LoadedScenario,
) -> Result<(TetMesh, Hexes), MeshError> {
    let mut hexes: Hexes = None;
    let m = match spec {
        MeshSpec::Box {
            origin,
            size,
            element_size,
            element: ElementKind::Tet4,
        } => mesh::generate::box_mesh(*origin, *size, *element_size),
        MeshSpec::Box {
            origin,
            size,
            element_size,
            element: ElementKind::Hex8,
        } => mesh::hex_tets::box_hex8(*origin, *size, *element_size).map(|s| {
            hexes = Some(s.hexes);
            s.mesh
        }),
        MeshSpec::Cylinder {
            center,
            radius,
            width,
            element_size,
            boundary,
        } => mesh::generate::cylinder_mesh(*center, *radius, *width, *element_size, *boundary),
        MeshSpec::Annulus {
            center,
            inner_radius,
            radius,
            width,
            element_size,
        } => mesh::generate::annulus_mesh(*center, *inner_radius, *radius, *width, *element_size),
        MeshSpec::Concentric {
            center,
            core_radius,
            radius,
            width,
            element_size,
        } => mesh::generate::concentric_cylinder_mesh(
            *center,
            *core_radius,
            *radius,
            *width,
            *element_size,
        ),
        MeshSpec::Nut {
            center,
            across_flats,
            hole_radius,
            thickness,
            per_side,
            radial,
            layers,
        } => mesh::nut::nut_mesh(
            *center,
            *across_flats,
            *hole_radius,
            *thickness,
            *per_side,
            *radial,
            *layers,
        ),
        MeshSpec::Container {
            center,
            inner_radius,
            wall,
            bottom,
            height,
            element_size,
        } => mesh::container::container_mesh(
            *center,
            *inner_radius,
            *wall,
            bottom.unwrap_or(*wall),
            *height,
            *element_size,
        ),
        MeshSpec::Checkpoint { .. } => unreachable!("checkpoint bodies are made from the file"),
        MeshSpec::Gmsh {
            file,
            element: ElementKind::Tet4,
        } => mesh::gmsh::read_msh(&sc.resolve(file)),
        MeshSpec::Gmsh {
            file,
            element: ElementKind::Hex8,
        } => mesh::gmsh::read_msh_hex8(&sc.resolve(file))
            .and_then(|hm| mesh::hex_tets::split_hex_mesh(&hm))
            .map(|s| {
                hexes = Some(s.hexes);
                s.mesh
            }),
    };
    m.map(|m| (m, hexes))
}

/// Whether body `b`'s Hex8 mesh (`source`, hexes `hexes`) can be run:
/// not jointed (joints work on tets), and each hex of one material (a
/// region's element set is a set of tets).
pub(super) fn hex8_allowed(
    b: &crate::scenario::BodySpec,
    source: &super::bodies::SourceMesh,
    hexes: &[[u32; 8]],
) -> Result<(), String> {
    let refuse = |what: &str| {
        Err(format!(
            "body `{}`: {what} works on Tet4 meshes; this mesh is Hex8 (element = \"hex8\")",
            b.name
        ))
    };
    if b.fracture.is_some() {
        return refuse("fracture");
    }
    for h in 0..hexes.len() {
        let m = &source.material[6 * h..6 * h + 6];
        if m.iter().any(|&x| x != m[0]) {
            return Err(format!(
                "body `{}`: Hex8 element {h} lies in two `regions` (its six tets differ in \
                 material); make each region a union of whole hexes",
                b.name
            ));
        }
    }
    Ok(())
}
