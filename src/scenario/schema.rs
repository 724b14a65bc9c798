//! The scenario schema (serde). Units are SI; temperatures in the user's
//! unit (K or °C, consistently).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::solver::SolverSpec;

/// A whole scenario file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Free text shown in the run summary.
    #[serde(default)]
    pub title: Option<String>,
    /// Time stepping.
    pub time: TimeSpec,
    /// Materials, referenced by name from bodies.
    pub materials: Vec<MaterialSpec>,
    /// Bodies: each a Tet4 mesh with a material and an initial state.
    pub bodies: Vec<BodySpec>,
    /// Free discrete-element spheres placed in boxes (issue 21).
    #[serde(default)]
    pub spheres: Vec<super::SphereSpec>,
    /// Thermal problem: integrator and boundary conditions. Absent: the
    /// default thermal problem, unless `[mechanics]` is given (then the run
    /// is purely mechanical and temperatures stay at their initial values).
    #[serde(default)]
    pub thermal: Option<ThermalSpec>,
    /// Explicit finite-strain mechanics (absent: bodies do not deform).
    #[serde(default)]
    pub mechanics: Option<MechanicsSpec>,
    /// Linear solver settings (PETSc).
    #[serde(default)]
    pub solver: SolverSpec,
    /// Output files.
    #[serde(default)]
    pub output: OutputSpec,
    /// Contact heat transfer between bodies (absent: bodies exchange no heat).
    #[serde(default)]
    pub contact: Option<ContactSpec>,
}

/// Contact heat transfer (seed 000 sec 3).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Default contact resistance Rc for every pair of materials (m² K / W:
    /// the flux is ΔT / Rc). Give `resistance` or `conductance`, not both.
    #[serde(default)]
    pub resistance: Option<f64>,
    /// Default contact conductance 1/Rc (W / m² / K).
    #[serde(default)]
    pub conductance: Option<f64>,
    /// Temperature drop: `local` (contact faces, default) or `average` (bodies' means).
    #[serde(default)]
    pub delta_t: crate::contact::DeltaT,
    /// Local-ΔT block form: `links` (default, bounded) or `rank_one`.
    #[serde(default)]
    pub operator: crate::contact::ContactOperator,
    /// Re-run detection every N steps (0: once, at the start).
    #[serde(default)]
    pub every: u64,
    /// Values for particular pairs of materials.
    #[serde(default)]
    pub pair: Vec<ContactPairSpec>,
    /// Heat across near-field gaps between bodies (issue 20).
    #[serde(default)]
    pub gap: Option<GapSpec>,
    /// Pressure-dependent conductance (Cooper–Mikic–Yovanovich) for every
    /// pair of materials, instead of `resistance` (issue 20).
    #[serde(default)]
    pub cmy: Option<crate::contact::conductance::Cmy>,
    /// Frictional heating of the penalty contact (issue 20), with mechanics.
    #[serde(default)]
    pub friction_heating: Option<FrictionHeatingSpec>,
    /// Tabular conductance h(T, P, gap) for every material pair (issue 20,
    /// seed 001 sec 7.1.4); a pair's own choice overrides it.
    #[serde(default)]
    pub table: Option<crate::contact::table::ConductanceTable>,
    /// Slip speed (m/s) above which a closed contact is *sliding* (the
    /// contact status of seed 001 sec 7.1.1). Default 1e-4 m/s.
    #[serde(default)]
    pub sliding_speed: Option<f64>,
}

/// The penalty friction's dissipated power turned into heat at the nodes
/// of the sliding tets (seed 001 sec 7.1.7: FHTG and FWGT).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionHeatingSpec {
    /// Fraction η of the friction work that becomes heat (default 1).
    #[serde(default = "one")]
    pub fraction: f64,
    /// Share w of the heat that goes to the searching body's tet, 1 − w
    /// to the other's (default 0.5).
    #[serde(default = "half")]
    pub weight: f64,
}

fn half() -> f64 {
    0.5
}

/// Heat across the gap between boundary faces of different bodies that
/// face each other closer than the pinball distance (seed 001 secs 7.1.1, 7.1.4–7.1.6):
/// gap conduction k/g, near-field convection h and grey-body radiation
/// σ F (T_a⁴ − T_b⁴), F = view factor / (1/ε_a + 1/ε_b − 1).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GapSpec {
    /// Pinball distance (m): faces farther apart exchange nothing. Default:
    /// half the largest tet extent.
    #[serde(default)]
    pub pinball: Option<f64>,
    /// Gaps below it (m) exchange heat as if this far apart, so k/g stays
    /// bounded as faces close. Default: 1 % of the pinball distance.
    #[serde(default)]
    pub min_gap: Option<f64>,
    /// Conductivity of the gap's medium k_gap (W/m/K), default 0.
    #[serde(default)]
    pub conductivity: f64,
    /// Near-field convection coefficient h_nf (W/m²/K), default 0.
    #[serde(default)]
    pub h: f64,
    /// Radiation across the gap, with the materials' emissivities.
    #[serde(default)]
    pub radiation: bool,
    /// View factor of the facing faces (default 1).
    #[serde(default = "one")]
    pub view_factor: f64,
    /// k_gap(T): the medium's conductivity against temperature (replaces
    /// `conductivity`), `{ temperature = [...], k = [...] }`.
    #[serde(default)]
    pub conductivity_table: Option<crate::contact::table::Table1>,
    /// The view factor against the gap (replaces `view_factor`),
    /// `{ gap = [...], value = [...] }`.
    #[serde(default)]
    pub view_factor_table: Option<crate::contact::table::Table1>,
}

fn one() -> f64 {
    1.0
}

/// Contact resistance between two materials.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactPairSpec {
    /// The two material names (order does not matter).
    pub materials: [String; 2],
    /// Rc for this pair.
    #[serde(default)]
    pub resistance: Option<f64>,
    /// 1/Rc for this pair.
    #[serde(default)]
    pub conductance: Option<f64>,
    /// Cooper–Mikic–Yovanovich conductance for this pair (issue 20).
    #[serde(default)]
    pub cmy: Option<crate::contact::conductance::Cmy>,
    /// Tabular conductance h(T, P, gap) for this pair (issue 20).
    #[serde(default)]
    pub table: Option<crate::contact::table::ConductanceTable>,
}

/// Resistance from a `resistance`/`conductance` choice (infinite: no contact heat).
pub fn contact_resistance(
    resistance: Option<f64>,
    conductance: Option<f64>,
) -> Result<Option<f64>, String> {
    match (resistance, conductance) {
        (Some(_), Some(_)) => Err("give `resistance` or `conductance`, not both".into()),
        (Some(r), None) if !(r.is_finite() && r > 0.0) => {
            Err(format!("resistance must be positive, got {r}"))
        }
        (Some(r), None) => Ok(Some(r)),
        (None, Some(g)) if !(g.is_finite() && g >= 0.0) => {
            Err(format!("conductance must be non-negative, got {g}"))
        }
        (None, Some(g)) => Ok(Some(if g == 0.0 { f64::INFINITY } else { 1.0 / g })),
        (None, None) => Ok(None),
    }
}

/// Time stepping: `dt` and either `steps` or `end_time`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Time step (s).
    pub dt: f64,
    /// Number of steps.
    #[serde(default)]
    pub steps: Option<u64>,
    /// End time (s); steps = round(end_time / dt).
    #[serde(default)]
    pub end_time: Option<f64>,
}

/// A material's thermal and mechanical properties. Thermal constants are
/// needed when the thermal problem runs, elastic ones when mechanics does.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Name bodies refer to.
    pub name: String,
    /// Thermal conductivity k (W/m/K).
    #[serde(default)]
    pub conductivity: Option<f64>,
    /// Specific heat c (J/kg/K).
    #[serde(default)]
    pub specific_heat: Option<f64>,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Young's modulus E (Pa).
    #[serde(default)]
    pub young: Option<f64>,
    /// Poisson's ratio ν.
    #[serde(default)]
    pub poisson: Option<f64>,
    /// Linear thermal expansion coefficient α (1/K), default 0.
    #[serde(default)]
    pub expansion: f64,
    /// Viscous damping η of the stress 2 η D (Pa s, seed 004 eq 35), default 0.
    #[serde(default)]
    pub viscosity: f64,
    /// Fracture: tensile strength f_t of the joints (Pa).
    #[serde(default)]
    pub tensile_strength: Option<f64>,
    /// Fracture: cohesion c, the shear strength without normal stress (Pa).
    #[serde(default)]
    pub cohesion: Option<f64>,
    /// Fracture: internal friction angle φ (degrees), shear strength
    /// c + σ_n tan φ under compression.
    #[serde(default)]
    pub friction_angle: Option<f64>,
    /// Fracture: mode I fracture energy G_I (J/m²).
    #[serde(default)]
    pub g_i: Option<f64>,
    /// Fracture: mode II fracture energy G_II (J/m²).
    #[serde(default)]
    pub g_ii: Option<f64>,
    /// Fracture: joint penalty p_f (Pa); a joint of size h has the
    /// stiffness p_f / h per unit area.
    #[serde(default)]
    pub fracture_penalty: Option<f64>,
    /// Fracture: Benzeggagh–Kenane exponent η of the mixed-mode energy
    /// G_I + (G_II − G_I) B^η (default 1).
    #[serde(default)]
    pub bk_exponent: Option<f64>,
    /// Surface emissivity ε in (0, 1] (radiation to the ambient, issue 20).
    #[serde(default)]
    pub emissivity: Option<f64>,
}

/// Joints that can break (issue 19): the body's tets of `set` made
/// discontinuous, tied by cohesive joints of `material`'s fracture keys.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractureSpec {
    /// Element set of the body's mesh (default: every tet).
    #[serde(default)]
    pub set: Option<String>,
    /// Material with the fracture keys (default: the body's material).
    #[serde(default)]
    pub material: Option<String>,
    /// Joints whose faces lie in this plane start broken: an initial crack.
    #[serde(default)]
    pub initial_crack: Option<CrackPlane>,
}

/// A plane of joint faces broken from the start.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrackPlane {
    /// A point of the plane (m, scenario coordinates).
    pub point: [f64; 3],
    /// Its normal (any length but zero).
    pub normal: [f64; 3],
}

/// An element set given by an axis-aligned box (m, scenario coordinates).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSet {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

/// One body.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Unique name; its named sets are addressed as `<name>.<set>`.
    pub name: String,
    /// Material name.
    pub material: String,
    /// Initial temperature.
    #[serde(default)]
    pub initial_temperature: f64,
    /// Where the mesh comes from.
    pub mesh: MeshSpec,
    /// Rotation (degrees) about x, then y, then z, through the origin,
    /// applied to the mesh before `translate`.
    #[serde(default)]
    pub rotate: Option<[f64; 3]>,
    /// Rigid translation applied to the mesh (m).
    #[serde(default)]
    pub translate: Option<[f64; 3]>,
    /// Prescribed rigid translation velocity (m/s): a kinematic body (a
    /// heated punch, a conveyor) whose contacts change as it moves. Needs
    /// `contact.every > 0` to see the changes.
    #[serde(default)]
    pub velocity: Option<[f64; 3]>,
    /// Replicate this body on a regular grid: bodies `<name>_i_j_k`.
    #[serde(default)]
    pub lattice: Option<LatticeSpec>,
    /// Replicate this body (a particle template) `count` times above a
    /// container, randomly oriented (dropped onto the heap by default, or
    /// stacked in a column): bodies `<name>_<i>`.
    #[serde(default)]
    pub pack: Option<PackSpec>,
    /// Mechanics: hold every node of the body in place (a container, a floor).
    #[serde(default)]
    pub fixed: bool,
    /// Mechanics: initial velocity of a free body (m/s).
    #[serde(default)]
    pub initial_velocity: Option<[f64; 3]>,
    /// Mechanics: stress-free temperature (default: the initial temperature).
    #[serde(default)]
    pub reference_temperature: Option<f64>,
    /// Mechanics without a thermal problem: the body's temperature rises
    /// uniformly from `initial_temperature` to `to` over `over` seconds.
    #[serde(default)]
    pub heating: Option<HeatingSpec>,
    /// Materials of element sets that differ from `material`, as
    /// `{ <element set> = "<material>" }` (a bonded multi-material body).
    #[serde(default)]
    pub regions: BTreeMap<String, String>,
    /// Element sets by position, `{ <name> = { min = [..], max = [..] } }`:
    /// the tets whose centroid lies in the box (after `rotate`/`translate`).
    #[serde(default)]
    pub element_sets: BTreeMap<String, BoxSet>,
    /// Cohesive joints between the tets of an element set, which break
    /// (mechanics only, issue 19): `{ set = "...", material = "..." }`.
    #[serde(default)]
    pub fracture: Option<FractureSpec>,
    /// This element set of the body is a bonded sphere lattice joined to
    /// the rest by ghost particles (mechanics only, issue 21):
    /// `{ set = "...", radius = ... }`.
    #[serde(default)]
    pub particles: Option<ParticlesSpec>,
}

/// An element set of a body made particles (issue 21, seed 002).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticlesSpec {
    /// Element set of the body's mesh.
    pub set: String,
    /// Sphere radius r (m); the lattice spacing is 2r.
    pub radius: f64,
}

/// A prescribed uniform temperature ramp.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeatingSpec {
    /// Final temperature.
    pub to: f64,
    /// Duration of the linear rise (s); 0 for a jump.
    #[serde(default)]
    pub over: f64,
}

/// A regular grid of copies of one body.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeSpec {
    /// Copies along x, y, z.
    pub count: [u32; 3],
    /// Offset between neighbouring copies (m).
    pub spacing: [f64; 3],
}

/// Particles dropped into a container (seed 000 sec 6).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PackSpec {
    /// Number of particles.
    pub count: usize,
    /// Seed of the random orientations (same seed, same placement).
    #[serde(default)]
    pub seed: u64,
    /// The body to fill: its mesh must be of kind `container`.
    pub into: String,
    /// How the particles are placed: `drop` (default: each particle's
    /// convex hull dropped at the lowest of `trials` random spots onto the
    /// floor or the particles before it) or `column` (a close-packed
    /// lattice of bounding spheres, a column about twice as tall).
    #[serde(default)]
    pub placement: Placement,
    /// Random spots tried per particle by the `drop` placement (default 8).
    #[serde(default = "default_trials")]
    pub trials: usize,
    /// Clearance (m) between the particles' convex hulls (`drop`, default a
    /// twentieth of the bounding radius) or bounding spheres (`column`,
    /// default a tenth).
    #[serde(default)]
    pub gap: Option<f64>,
    /// Largest solid fraction the container can hold (the capacity check
    /// before any work): default 0.64, random close packing of spheres.
    #[serde(default = "default_max_fraction")]
    pub max_fraction: f64,
    /// Place the particles from a CSV file instead (relative to the
    /// scenario): one line `x, y, z, rx, ry, rz` per particle (centroid in
    /// m, rotations in degrees about x then y then z); `#` comments.
    #[serde(default)]
    pub positions: Option<String>,
}

fn default_max_fraction() -> f64 {
    0.64
}

fn default_trials() -> usize {
    8
}

/// How a pack's particles are placed before they are dropped.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// Sequential drop of each particle's convex hull
    /// (`geometry::placement::drop_sites`).
    #[default]
    Drop,
    /// Close-packed lattice of bounding spheres
    /// (`geometry::placement::column_sites`).
    Column,
}

/// Mesh source of a body.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MeshSpec {
    /// A structured box split into Tet4 (named sets xmin, xmax, ymin, ymax, zmin, zmax).
    Box {
        /// Lower corner (m).
        #[serde(default)]
        origin: [f64; 3],
        /// Edge lengths (m).
        size: [f64; 3],
        /// Target element size h (m): round(L/h) cells per axis.
        element_size: f64,
        /// `tet4` (default: six tets per cell) or `hex8` (one hexahedron
        /// per cell, issue 21).
        #[serde(default)]
        element: ElementKind,
    },
    /// A solid cylinder (disc) with its axis along z (named sets side, zmin, zmax).
    Cylinder {
        /// Centre (m).
        #[serde(default)]
        center: [f64; 3],
        /// Radius (m).
        radius: f64,
        /// Width along z (m).
        width: f64,
        /// Target element size h (m).
        element_size: f64,
        /// Where the boundary nodes lie: `inscribed` (on the circle, the
        /// default) or `area_preserving` (just outside it, so the faceted
        /// section has the circle's area; see `mesh::generate::CircleNodes`).
        #[serde(default)]
        boundary: crate::mesh::generate::CircleNodes,
    },
    /// A hollow cylinder, axis along z (named sets inner, outer, zmin, zmax).
    Annulus {
        /// Centre (m): the body spans z = center.z ± width / 2.
        #[serde(default)]
        center: [f64; 3],
        /// Inner radius (m).
        inner_radius: f64,
        /// Outer radius (m).
        radius: f64,
        /// Width along z (m).
        width: f64,
        /// Target element size h (m).
        element_size: f64,
    },
    /// A solid core bonded inside a ring, one conforming mesh, axis along z
    /// (element sets core, ring; node/face sets outer, interface, zmin, zmax).
    Concentric {
        /// Centre (m): the body spans z = center.z ± width / 2.
        #[serde(default)]
        center: [f64; 3],
        /// Core radius (m).
        core_radius: f64,
        /// Outer radius (m).
        radius: f64,
        /// Width along z (m).
        width: f64,
        /// Target element size h (m).
        element_size: f64,
    },
    /// A hexagonal nut with a round hole, axis along z, centred on
    /// `center` (named sets outer, hole, zmin, zmax). The defaults are the
    /// 144-tet nut for seed 000 Fig 17 (see `mesh::nut`).
    Nut {
        /// Centroid (m).
        #[serde(default)]
        center: [f64; 3],
        /// Width across flats (m).
        #[serde(default = "default_nut_width")]
        across_flats: f64,
        /// Hole radius (m).
        #[serde(default = "default_nut_hole")]
        hole_radius: f64,
        /// Thickness along z (m).
        #[serde(default = "default_nut_thickness")]
        thickness: f64,
        /// Segments per hexagon side.
        #[serde(default = "default_nut_per_side")]
        per_side: usize,
        /// Element layers between hole and flats.
        #[serde(default = "default_nut_radial")]
        radial: usize,
        /// Element layers through the thickness.
        #[serde(default = "default_nut_layers")]
        layers: usize,
    },
    /// An open cylindrical container with a floor, axis along z, the
    /// floor's top at `center` (named sets inner, outer, rim, floor, wall_inner).
    Container {
        /// Centre of the floor's top face (m).
        #[serde(default)]
        center: [f64; 3],
        /// Inner radius (m).
        inner_radius: f64,
        /// Wall thickness (m).
        wall: f64,
        /// Floor thickness (m), default the wall's.
        #[serde(default)]
        bottom: Option<f64>,
        /// Inner height above the floor (m).
        height: f64,
        /// Target element size (m).
        element_size: f64,
    },
    /// Bodies from an fdem checkpoint, in their positions there (the
    /// deformed state becomes this run's reference): all bodies that came
    /// from the scenario entry `template` (e.g. every particle of a pack).
    Checkpoint {
        /// Checkpoint file, relative to the scenario.
        file: String,
        /// Name of the scenario entry the bodies came from.
        template: String,
    },
    /// A Gmsh MSH 4.1 file (ASCII or binary); physical groups become named sets.
    Gmsh {
        /// Path, relative to the scenario file.
        file: String,
        /// `tet4` (default: the file's tetrahedra) or `hex8` (its 8-node
        /// hexahedra, issue 21).
        #[serde(default)]
        element: ElementKind,
    },
}

/// The finite element of a body's own mesh (issue 21).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// Linear tetrahedra.
    #[default]
    Tet4,
    /// Trilinear hexahedra (seed 002 eqs 6–7), selective-reduced with
    /// hourglass control; also split into six tets for contact and output.
    Hex8,
}

fn default_nut_width() -> f64 {
    crate::mesh::nut::NUT_ACROSS_FLATS
}
fn default_nut_hole() -> f64 {
    crate::mesh::nut::NUT_HOLE_RADIUS
}
fn default_nut_thickness() -> f64 {
    crate::mesh::nut::NUT_THICKNESS
}
// The nut's divisions default to the generator's (`mesh::nut::NUT_DIVISIONS`).
fn default_nut_per_side() -> usize {
    crate::mesh::nut::NUT_DIVISIONS.0
}
fn default_nut_radial() -> usize {
    crate::mesh::nut::NUT_DIVISIONS.1
}
fn default_nut_layers() -> usize {
    crate::mesh::nut::NUT_DIVISIONS.2
}

/// Capacity matrix form.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CapacityKind {
    /// Consistent mass matrix (seed 000 eq 15): undershoots where a step
    /// is short against h²/α (README, "Bounds").
    Consistent,
    /// Row-sum lumped (diagonal), the default: with θ = 1 and a mesh
    /// without obtuse couplings (or `conduction = "bounded"`) every
    /// temperature stays within its initial and boundary values.
    #[default]
    Lumped,
}

/// How the conduction (and convection) operator is formed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConductionKind {
    /// The Galerkin matrices as assembled (seed 000 eqs 16–17).
    #[default]
    Galerkin,
    /// Positive couplings of the assembled operator moved to its diagonal
    /// (discrete upwinding): the discrete maximum principle holds on any
    /// mesh with lumped capacity (`thermal::monotone`).
    Bounded,
}

/// The thermal problem.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    /// θ of the theta method (seed 000 eq 22): 0 explicit, 0.5 Crank–Nicolson, 1 backward Euler.
    #[serde(default = "default_theta")]
    pub theta: f64,
    /// Capacity matrix form.
    #[serde(default)]
    pub capacity: CapacityKind,
    /// Conduction operator form.
    #[serde(default)]
    pub conduction: ConductionKind,
    /// Boundary conditions and sources.
    #[serde(default)]
    pub bc: Vec<ThermalBcSpec>,
    /// Initial temperatures on named sets (override the body's value).
    #[serde(default)]
    pub initial: Vec<InitialSpec>,
    /// Added to every temperature to make it absolute (K) where radiation
    /// needs it: 273.15 for °C input, 0 for kelvin (seed 001's TOFFST).
    #[serde(default)]
    pub temperature_offset: f64,
    /// Heat exchange of the free surfaces with the surroundings.
    #[serde(default)]
    pub ambient: Option<AmbientSpec>,
}

/// Convection and radiation of the bodies' free surfaces to an ambient
/// (issue 20): on every boundary face, less the area in contact with
/// another body.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AmbientSpec {
    /// Ambient temperature (scenario unit; plus the offset for radiation).
    pub temperature: f64,
    /// Convection coefficient h (W/m²/K), default 0.
    #[serde(default)]
    pub h: f64,
    /// Radiate with each material's emissivity, ε σ (T⁴ − T_env⁴).
    #[serde(default)]
    pub radiation: bool,
    /// The bodies (names or scenario entries) that exchange heat with the
    /// ambient; default all.
    #[serde(default)]
    pub bodies: Vec<String>,
}

fn default_theta() -> f64 {
    1.0
}

impl Default for ThermalSpec {
    fn default() -> Self {
        ThermalSpec {
            theta: default_theta(),
            capacity: CapacityKind::default(),
            conduction: ConductionKind::default(),
            bc: Vec::new(),
            initial: Vec::new(),
            temperature_offset: 0.0,
            ambient: None,
        }
    }
}

/// An initial temperature on a named set.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Node or face set (`<body>.<set>`, or `<set>` when unambiguous).
    pub set: String,
    /// Temperature.
    pub value: f64,
}

/// Thermal boundary conditions and sources.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ThermalBcSpec {
    /// Prescribed temperature (Dirichlet) on the nodes of a set.
    Temperature {
        /// Node or face set.
        set: String,
        /// Temperature.
        value: f64,
        /// Seconds over which the value is reached linearly from the
        /// nodes' initial temperature (default: at once).
        #[serde(default)]
        ramp: Option<f64>,
    },
    /// Prescribed heat flux into the body (W/m²) on a face set (seed 000 eq 18).
    Flux {
        /// Face set.
        set: String,
        /// Flux, positive into the body.
        value: f64,
    },
    /// Convection q = h (T − T_env) out of the body on a face set (seed 000 eq 20).
    Convection {
        /// Face set.
        set: String,
        /// Film coefficient h (W/m²/K).
        h: f64,
        /// Ambient temperature T_env.
        ambient: f64,
    },
    /// Uniform volumetric heat source (W/m³) in a body (seed 000 eq 17).
    Source {
        /// Body name.
        body: String,
        /// Source density.
        value: f64,
    },
}

/// Output settings.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Directory (default `output/<stem>`; `--output` overrides).
    #[serde(default)]
    pub directory: Option<String>,
    /// File stem (default: the scenario file's stem).
    #[serde(default)]
    pub stem: Option<String>,
    /// Write a field step every N steps (0 or absent: only at `times`, start and end).
    #[serde(default)]
    pub every: Option<u64>,
    /// Also write at these times (rounded to the nearest step).
    #[serde(default)]
    pub times: Vec<f64>,
    /// Write a restart checkpoint (`<stem>_checkpoint.h5`) at the end of
    /// the run (and when the packing settles).
    #[serde(default)]
    pub checkpoint: bool,
    /// Also overwrite the checkpoint every N steps (0: only at the end).
    #[serde(default)]
    pub checkpoint_every: u64,
    /// Also write a history row every N steps between field steps (0: only
    /// with the fields).
    #[serde(default)]
    pub history_every: u64,
    /// Particle statistics: CSV and PNG of the particles' temperatures.
    #[serde(default)]
    pub particles: Option<ParticleOutputSpec>,
}

/// Temperature statistics over many particles (seed 000 sec 6, Fig 20).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleOutputSpec {
    /// Bodies that came from this scenario entry are the particles.
    pub template: String,
    /// Vertical axis (x, y) for the temperature-against-radius profile.
    #[serde(default)]
    pub axis: [f64; 2],
    /// Radial bins of the profile.
    #[serde(default = "default_bins")]
    pub radial_bins: usize,
    /// Times of the radial profiles (s; default: 4 evenly spaced).
    #[serde(default)]
    pub radial_times: Vec<f64>,
}

fn default_bins() -> usize {
    8
}

/// Explicit finite-strain mechanics (seed 004 sec 2; seed 000 sec 3.4 for
/// where it sits in the step).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MechanicsSpec {
    /// Explicit time step (s). Default: `safety` × the critical step of
    /// the mesh, materials and contact penalty. A larger value is an error.
    #[serde(default)]
    pub dt: Option<f64>,
    /// Fraction of the critical step used by default (0 < safety ≤ 1).
    #[serde(default = "default_safety")]
    pub safety: f64,
    /// Explicit substeps per `time.dt`. Absent: as many as `time.dt` needs
    /// (the mechanical and thermal clocks agree). Given: the mechanics
    /// advances `substeps` × dt per thermal step — a quasi-static coupling
    /// in which the mechanical time is decoupled from the thermal time.
    #[serde(default)]
    pub substeps: Option<u64>,
    /// Gravitational acceleration (m/s²).
    #[serde(default)]
    pub gravity: [f64; 3],
    /// Mass-proportional damping coefficient c (1/s): force −c m v.
    #[serde(default)]
    pub damping: f64,
    /// Mass-proportional damping (1/s) of a body that touches no other
    /// body in the substep (free flight). Absent: `damping` everywhere. A
    /// packing stage sets it below `damping` (the deposit: 5 against 10) so
    /// particles fall nearly freely and are damped once they land; needs
    /// `contact`.
    #[serde(default)]
    pub free_damping: Option<f64>,
    /// Boundary conditions on named sets.
    #[serde(default)]
    pub bc: Vec<MechanicsBcSpec>,
    /// Penalty contact between bodies (absent: bodies pass through each other).
    #[serde(default)]
    pub contact: Option<PenaltySpec>,
    /// Stop the run once the bodies have settled (deposition).
    #[serde(default)]
    pub settle: Option<SettleSpec>,
    /// Repartition the bodies over the ranks as they move (runs on
    /// several ranks).
    #[serde(default)]
    pub rebalance: RebalanceSpec,
}

/// When a run on several ranks repartitions its bodies: every `every`
/// steps (`time.dt`; 0: never) the work per rank (elements and the
/// contact pairs its bodies found, in the partition's units) is compared
/// with the mean, and when the largest exceeds `threshold` × the mean the
/// bodies are cut again by recursive coordinate bisection over their
/// current centres, weighted by their work; their state moves with them.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RebalanceSpec {
    /// Largest max/mean work per rank tolerated (> 1).
    #[serde(default = "default_rebalance_threshold")]
    pub threshold: f64,
    /// Steps between checks (0: never repartition).
    #[serde(default = "default_rebalance_every")]
    pub every: u64,
}

impl Default for RebalanceSpec {
    fn default() -> Self {
        RebalanceSpec {
            threshold: default_rebalance_threshold(),
            every: default_rebalance_every(),
        }
    }
}

fn default_rebalance_threshold() -> f64 {
    1.1
}

fn default_rebalance_every() -> u64 {
    10
}

/// When a deposition has settled: the kinetic energy, checked after every
/// step (`time.dt`) from `after` on, falls below `kinetic_energy` (J),
/// below `relative` × the largest kinetic energy seen so far, or below
/// ½ M v² for the free bodies' mass M and `rms_speed` v (the same
/// criterion for any number of particles).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettleSpec {
    /// Absolute threshold (J).
    #[serde(default)]
    pub kinetic_energy: Option<f64>,
    /// Threshold relative to the peak kinetic energy.
    #[serde(default)]
    pub relative: Option<f64>,
    /// Root-mean-square speed (m/s) of the free bodies' mass.
    #[serde(default)]
    pub rms_speed: Option<f64>,
    /// Earliest time to stop (s).
    #[serde(default)]
    pub after: f64,
}

fn default_safety() -> f64 {
    crate::mechanics::explicit::DEFAULT_SAFETY
}

/// Mechanical boundary conditions.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MechanicsBcSpec {
    /// Hold the nodes of a set (all components, or those listed: "x", "y", "z").
    Fixed {
        /// Node or face set.
        set: String,
        /// Components to hold (default all).
        #[serde(default)]
        components: Option<Vec<String>>,
    },
    /// Prescribed velocity (m/s) on the nodes of a set; a component given
    /// as NaN is left free.
    Velocity {
        /// Node or face set.
        set: String,
        /// Velocity.
        value: [f64; 3],
    },
    /// Traction (Pa) on a face set: a dead load on the reference area.
    Traction {
        /// Face set.
        set: String,
        /// Traction vector.
        value: [f64; 3],
    },
}

/// Penalty contact (Munjiza's FDEM contact is potential-based; fdem uses a
/// volume-overlap potential, see `contact::penalty`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltySpec {
    /// Penalty number p_n (Pa), typically 10–100 × Young's modulus.
    pub penalty: f64,
    /// Coulomb friction coefficient μ.
    #[serde(default)]
    pub friction: f64,
    /// Normal contact damping as a fraction of critical.
    #[serde(default)]
    pub damping_ratio: f64,
    /// Sliding speed below which friction is regularised (m/s).
    #[serde(default = "default_slip")]
    pub slip_velocity: f64,
    /// Search margin (m) of the contact candidate lists; default half the
    /// smallest element length.
    #[serde(default)]
    pub margin: Option<f64>,
    /// Linearised contact (`contact::penalty::LinearizedOverlap`): between
    /// exact evaluations, a contacting pair's overlap volume follows its
    /// first-order Taylor model while its nodes move less than this
    /// fraction of the overlap's depth relative to each other. 0 (default):
    /// every pair exact every substep. Candidates are then re-detected at
    /// the start of every step, so a restart repeats the run bitwise.
    #[serde(default)]
    pub linear_tolerance: f64,
    /// Tangential spring k_t / k_n of Coulomb friction with stick
    /// (`contact::penalty::penalty_forces_with`): each touching tet pair
    /// keeps its tangential spring's force from substep to substep
    /// (across detections, repartitions and restarts) and slides only at
    /// μ F_n. 0 (default): regularised friction (creeps below μ F_n at
    /// speeds up to `slip_velocity`).
    #[serde(default)]
    pub tangential_stiffness: f64,
    /// Factor M ≥ 1 on the regularised friction's explicit stick limit
    /// (`contact::penalty::PenaltyParams::stick_limit`): below
    /// M μ F_n Δt / m* friction is viscous. 1 (default) bounds each pair's
    /// damper alone; 2 keeps a node under the dampers of several pairs
    /// from chattering (docs/guide.md, "Friction chatter").
    #[serde(default = "default_stick_limit")]
    pub stick_limit: f64,
}

fn default_slip() -> f64 {
    1e-6
}

fn default_stick_limit() -> f64 {
    1.0
}
