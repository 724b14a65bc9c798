//! The scenario schema (serde). Units are SI; temperatures in the user's
//! unit (K or °C, consistently).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

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
    /// Thermal problem: integrator and boundary conditions.
    #[serde(default)]
    pub thermal: ThermalSpec,
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
    /// Re-run detection every N steps (0: once, at the start).
    #[serde(default)]
    pub every: u64,
    /// Values for particular pairs of materials.
    #[serde(default)]
    pub pair: Vec<ContactPairSpec>,
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

/// A material's thermal properties.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Name bodies refer to.
    pub name: String,
    /// Thermal conductivity k (W/m/K).
    pub conductivity: f64,
    /// Specific heat c (J/kg/K).
    pub specific_heat: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
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
    },
    /// A Gmsh MSH 4.1 file (ASCII or binary); physical groups become named sets.
    Gmsh {
        /// Path, relative to the scenario file.
        file: String,
    },
}

/// Capacity matrix form.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CapacityKind {
    /// Consistent mass matrix (seed 000 eq 15).
    #[default]
    Consistent,
    /// Row-sum lumped (diagonal).
    Lumped,
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
    /// Boundary conditions and sources.
    #[serde(default)]
    pub bc: Vec<ThermalBcSpec>,
    /// Initial temperatures on named sets (override the body's value).
    #[serde(default)]
    pub initial: Vec<InitialSpec>,
}

fn default_theta() -> f64 {
    1.0
}

impl Default for ThermalSpec {
    fn default() -> Self {
        ThermalSpec {
            theta: default_theta(),
            capacity: CapacityKind::default(),
            bc: Vec::new(),
            initial: Vec::new(),
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

/// Linear solver settings. Anything here can also be given on the command
/// line as a PETSc option, which wins.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// KSP type (`-ksp_type`); default chosen by problem size (see README).
    #[serde(default)]
    pub ksp_type: Option<String>,
    /// PC type (`-pc_type`).
    #[serde(default)]
    pub pc_type: Option<String>,
    /// Relative tolerance (`-ksp_rtol`), default 1e-10.
    #[serde(default)]
    pub rtol: Option<f64>,
    /// Absolute tolerance (`-ksp_atol`), default 1e-50.
    #[serde(default)]
    pub atol: Option<f64>,
    /// Iteration cap (`-ksp_max_it`), default 10000.
    #[serde(default)]
    pub max_it: Option<u32>,
    /// Any other PETSc options, without the leading dash: `{ ksp_monitor = "" }`.
    #[serde(default)]
    pub options: BTreeMap<String, String>,
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
}

impl Scenario {
    /// Number of steps implied by `time`.
    pub fn num_steps(&self) -> u64 {
        match (self.time.steps, self.time.end_time) {
            (Some(n), _) => n,
            (None, Some(t)) => (t / self.time.dt).round() as u64,
            (None, None) => 0,
        }
    }

    /// Check values and cross-references; returns (key path, message).
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        let t = &self.time;
        if !(t.dt.is_finite() && t.dt > 0.0) {
            return bad(
                "time.dt",
                format!("must be a positive number, got {}", t.dt),
            );
        }
        match (t.steps, t.end_time) {
            (Some(_), Some(_)) => {
                return bad("time", "give either `steps` or `end_time`, not both".into())
            }
            (None, None) => return bad("time", "give `steps` or `end_time`".into()),
            (None, Some(e)) if !(e.is_finite() && e > 0.0) => {
                return bad("time.end_time", format!("must be positive, got {e}"))
            }
            _ => {}
        }
        let th = self.thermal.theta;
        if !(0.0..=1.0).contains(&th) {
            return bad("thermal.theta", format!("must be in [0, 1], got {th}"));
        }
        if self.materials.is_empty() {
            return bad("materials", "at least one material is needed".into());
        }
        for (i, m) in self.materials.iter().enumerate() {
            for (field, v) in [
                ("conductivity", m.conductivity),
                ("specific_heat", m.specific_heat),
                ("density", m.density),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return bad(
                        &format!("materials[{i}].{field}"),
                        format!("must be a positive number, got {v} (material `{}`)", m.name),
                    );
                }
            }
            if self.materials[..i].iter().any(|o| o.name == m.name) {
                return bad(
                    &format!("materials[{i}].name"),
                    format!("duplicate material `{}`", m.name),
                );
            }
        }
        if self.bodies.is_empty() {
            return bad("bodies", "at least one body is needed".into());
        }
        for (i, b) in self.bodies.iter().enumerate() {
            let key = |f: &str| format!("bodies[{i}].{f}");
            if b.name.is_empty() || b.name.contains('.') {
                return bad(
                    &key("name"),
                    format!("`{}`: must be non-empty without dots", b.name),
                );
            }
            if self.bodies[..i].iter().any(|o| o.name == b.name) {
                return bad(&key("name"), format!("duplicate body `{}`", b.name));
            }
            if !self.materials.iter().any(|m| m.name == b.material) {
                return bad(
                    &key("material"),
                    format!("no material named `{}`", b.material),
                );
            }
            if !b.initial_temperature.is_finite() {
                return bad(&key("initial_temperature"), "must be finite".into());
            }
            if let MeshSpec::Box {
                size,
                element_size,
                origin,
            } = &b.mesh
            {
                if size.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
                    return bad(&key("mesh.size"), format!("must be positive, got {size:?}"));
                }
                if !(element_size.is_finite() && *element_size > 0.0) {
                    return bad(
                        &key("mesh.element_size"),
                        format!("must be positive, got {element_size}"),
                    );
                }
                if origin.iter().any(|o| !o.is_finite()) {
                    return bad(&key("mesh.origin"), "must be finite".into());
                }
            }
        }
        if let Some(c) = &self.contact {
            contact_resistance(c.resistance, c.conductance)
                .map_err(|m| ("contact".to_string(), m))?;
            for (i, p) in c.pair.iter().enumerate() {
                let key = format!("contact.pair[{i}]");
                match contact_resistance(p.resistance, p.conductance) {
                    Err(m) => return bad(&key, m),
                    Ok(None) => return bad(&key, "give `resistance` or `conductance`".into()),
                    Ok(Some(_)) => {}
                }
                for m in &p.materials {
                    if !self.materials.iter().any(|x| &x.name == m) {
                        return bad(
                            &format!("{key}.materials"),
                            format!("no material named `{m}`"),
                        );
                    }
                }
            }
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if let MeshSpec::Cylinder {
                radius,
                width,
                element_size,
                center,
            } = &b.mesh
            {
                for (f, v) in [
                    ("radius", radius),
                    ("width", width),
                    ("element_size", element_size),
                ] {
                    if !(v.is_finite() && *v > 0.0) {
                        return bad(
                            &format!("bodies[{i}].mesh.{f}"),
                            format!("must be positive, got {v}"),
                        );
                    }
                }
                if center.iter().any(|c| !c.is_finite()) {
                    return bad(&format!("bodies[{i}].mesh.center"), "must be finite".into());
                }
            }
            if let Some(l) = &b.lattice {
                if l.count.contains(&0) || l.spacing.iter().any(|x| !x.is_finite()) {
                    return bad(
                        &format!("bodies[{i}].lattice"),
                        "counts must be positive and spacings finite".into(),
                    );
                }
            }
            if let Some(v) = b.velocity {
                if v.iter().any(|x| !x.is_finite()) {
                    return bad(&format!("bodies[{i}].velocity"), "must be finite".into());
                }
                let every = self.contact.as_ref().map_or(0, |c| c.every);
                if v != [0.0; 3] && self.contact.is_some() && every == 0 {
                    return bad(
                        &format!("bodies[{i}].velocity"),
                        "a moving body needs `contact.every` > 0 to re-detect its contacts".into(),
                    );
                }
            }
            if let Some(r) = b.rotate {
                if r.iter().any(|x| !x.is_finite()) {
                    return bad(&format!("bodies[{i}].rotate"), "must be finite".into());
                }
            }
        }
        for (i, bc) in self.thermal.bc.iter().enumerate() {
            let key = |f: &str| format!("thermal.bc[{i}].{f}");
            match bc {
                ThermalBcSpec::Temperature { value, .. } | ThermalBcSpec::Flux { value, .. } => {
                    if !value.is_finite() {
                        return bad(&key("value"), "must be finite".into());
                    }
                }
                ThermalBcSpec::Convection { h, ambient, .. } => {
                    if !(h.is_finite() && *h >= 0.0) {
                        return bad(&key("h"), format!("must be non-negative, got {h}"));
                    }
                    if !ambient.is_finite() {
                        return bad(&key("ambient"), "must be finite".into());
                    }
                }
                ThermalBcSpec::Source { body, value } => {
                    if !value.is_finite() {
                        return bad(&key("value"), "must be finite".into());
                    }
                    if !self.bodies.iter().any(|b| &b.name == body) {
                        return bad(&key("body"), format!("no body named `{body}`"));
                    }
                }
            }
        }
        if let Some(r) = self.solver.rtol {
            if !(r > 0.0 && r < 1.0) {
                return bad("solver.rtol", format!("must be in (0, 1), got {r}"));
            }
        }
        for (i, t) in self.output.times.iter().enumerate() {
            if !(t.is_finite() && *t >= 0.0) {
                return bad(
                    &format!("output.times[{i}]"),
                    format!("must be non-negative, got {t}"),
                );
            }
        }
        Ok(())
    }
}
