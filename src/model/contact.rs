//! Contact heat transfer resolved to material indices: per material pair
//! the conductance model (a constant Rc, Cooper–Mikic–Yovanovich, or a
//! table), the near-field gap and frictional heating settings.

use crate::contact::conductance::Cmy;
use crate::contact::table::ConductanceTable;
use crate::contact::{ContactOperator, DeltaT};
use crate::scenario::{contact_resistance, ContactSpec, FrictionHeatingSpec, GapSpec};

use super::Material;

/// Default slip speed above which a closed contact is sliding (m/s).
pub const SLIDING_SPEED: f64 = 1e-4;

/// Contact heat transfer settings resolved to material indices.
#[derive(Debug, Clone)]
pub struct ContactModel {
    /// Rc between materials i and j (symmetric; infinite: no heat).
    pub resistance: Vec<Vec<f64>>,
    /// How ΔT is taken.
    pub delta_t: DeltaT,
    /// The local-ΔT block form.
    pub operator: ContactOperator,
    /// Detection cadence in steps (0: once).
    pub every: u64,
    /// Near-field gap heat (issue 20).
    pub gap: Option<GapSpec>,
    /// Pressure-dependent conductance between materials i and j, if any.
    pub cmy: Vec<Vec<Option<Cmy>>>,
    /// The conductance tables of the scenario.
    pub tables: Vec<ConductanceTable>,
    /// Tabular conductance between materials i and j (an index into
    /// `tables`), if any; it overrides `resistance` and `cmy`.
    pub table: Vec<Vec<Option<usize>>>,
    /// Frictional heating (η, w), when on.
    pub friction_heating: Option<FrictionHeatingSpec>,
    /// Slip speed above which a closed contact is sliding (m/s).
    pub sliding_speed: f64,
}

impl ContactModel {
    /// The table of materials `a` and `b`, if they have one.
    pub fn table_of(&self, a: u32, b: u32) -> Option<&ConductanceTable> {
        self.table[a as usize][b as usize].map(|i| &self.tables[i])
    }

    /// Whether some material pair's conductance depends on temperature
    /// (the thermal step is then nonlinear), or the gap medium's k does.
    pub fn temperature_dependent(&self) -> bool {
        self.tables.iter().any(|t| t.depends_on_temperature())
            || self
                .gap
                .as_ref()
                .is_some_and(|g| g.conductivity_table.as_ref().is_some_and(|k| k.x.len() > 1))
    }

    /// Whether some table depends on the penetration of closed contacts.
    pub fn needs_penetration(&self) -> bool {
        self.tables.iter().any(|t| t.depends_on_gap())
    }
}

/// Resolve `[contact]` against the materials. A pair's own choice (Rc,
/// CMY or a table) replaces the defaults for that pair.
pub fn contact_model(c: &ContactSpec, materials: &[Material]) -> Result<ContactModel, String> {
    let default = contact_resistance(c.resistance, c.conductance)?;
    let default = default.unwrap_or(f64::INFINITY);
    let nm = materials.len();
    let mut rc = vec![vec![default; nm]; nm];
    let mut cmy = vec![vec![c.cmy; nm]; nm];
    let mut tables: Vec<ConductanceTable> = c.table.iter().cloned().collect();
    let mut table = vec![vec![c.table.as_ref().map(|_| 0); nm]; nm];
    for (i, p) in c.pair.iter().enumerate() {
        let r = contact_resistance(p.resistance, p.conductance)
            .map_err(|m| format!("contact.pair[{i}]: {m}"))?;
        let idx = |n: &str| materials.iter().position(|m| m.name == n).unwrap();
        let (a, b) = (idx(&p.materials[0]), idx(&p.materials[1]));
        let own = r.is_some() || p.cmy.is_some() || p.table.is_some();
        if !own {
            continue;
        }
        let r = r.unwrap_or(f64::INFINITY);
        (rc[a][b], rc[b][a]) = (r, r);
        (cmy[a][b], cmy[b][a]) = (p.cmy, p.cmy);
        let t = p.table.as_ref().map(|t| {
            tables.push(t.clone());
            tables.len() - 1
        });
        (table[a][b], table[b][a]) = (t, t);
    }
    Ok(ContactModel {
        resistance: rc,
        delta_t: c.delta_t,
        operator: c.operator,
        every: c.every,
        gap: c.gap.clone(),
        cmy,
        tables,
        table,
        friction_heating: c.friction_heating,
        sliding_speed: c.sliding_speed.unwrap_or(SLIDING_SPEED),
    })
}

impl super::Model {
    /// Contact resistance between materials `a` and `b` (infinite without
    /// contact heat transfer).
    pub fn resistance(&self, a: u32, b: u32) -> f64 {
        self.contact
            .as_ref()
            .map_or(f64::INFINITY, |c| c.resistance[a as usize][b as usize])
    }
}
