//! Scenario methods: derived settings and the validation of values and
//! cross-references, with errors naming the dotted key.

use super::schema::*;

impl Scenario {
    /// Whether the thermal problem is solved.
    pub fn has_thermal(&self) -> bool {
        self.thermal.is_some() || self.mechanics.is_none()
    }

    /// The thermal settings (defaults when absent).
    pub fn thermal_spec(&self) -> ThermalSpec {
        self.thermal.clone().unwrap_or_default()
    }

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
        let thermal = self.thermal_spec();
        let th = thermal.theta;
        if !(0.0..=1.0).contains(&th) {
            return bad("thermal.theta", format!("must be in [0, 1], got {th}"));
        }
        if thermal.conduction == ConductionKind::Bounded
            && thermal.capacity == CapacityKind::Consistent
        {
            return bad(
                "thermal.conduction",
                "\"bounded\" needs thermal.capacity = \"lumped\" (a consistent capacity \
                 couples neighbouring nodes positively and cannot keep the bounds)"
                    .into(),
            );
        }
        if self.materials.is_empty() {
            return bad("materials", "at least one material is needed".into());
        }
        for (i, m) in self.materials.iter().enumerate() {
            let mut fields = vec![("density", Some(m.density))];
            if self.has_thermal() {
                fields.push(("conductivity", m.conductivity));
                fields.push(("specific_heat", m.specific_heat));
            }
            for (field, v) in fields {
                let Some(v) = v else {
                    return bad(
                        &format!("materials[{i}].{field}"),
                        format!(
                            "missing (material `{}`): the thermal problem needs it",
                            m.name
                        ),
                    );
                };
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
            for (set, mat) in &b.regions {
                if !self.materials.iter().any(|m| &m.name == mat) {
                    return bad(
                        &key(&format!("regions.{set}")),
                        format!("no material named `{mat}`"),
                    );
                }
            }
            if let Some(h) = &b.heating {
                if self.has_thermal() {
                    return bad(
                        &key("heating"),
                        "a prescribed heating needs a run without a thermal problem \
                         (no [thermal] table, with [mechanics])"
                            .into(),
                    );
                }
                if !(h.to.is_finite() && h.over.is_finite() && h.over >= 0.0) {
                    return bad(&key("heating"), "`to` must be finite, `over` >= 0".into());
                }
            }
            if b.fixed && (b.velocity.is_some() || b.initial_velocity.is_some()) {
                return bad(
                    &key("fixed"),
                    "a fixed body cannot also have a velocity".into(),
                );
            }
            for (f, v) in [
                ("initial_velocity", b.initial_velocity),
                (
                    "reference_temperature",
                    b.reference_temperature.map(|t| [t; 3]),
                ),
            ] {
                if v.is_some_and(|v| v.iter().any(|x| !x.is_finite())) {
                    return bad(&key(f), "must be finite".into());
                }
            }
            if let Some(p) = &b.pack {
                if b.lattice.is_some() {
                    return bad(&key("pack"), "give `pack` or `lattice`, not both".into());
                }
                if p.count == 0 {
                    return bad(&key("pack.count"), "must be at least 1".into());
                }
                if p.gap.is_some_and(|g| !(g.is_finite() && g >= 0.0)) {
                    return bad(&key("pack.gap"), "must be finite and >= 0".into());
                }
                if !(p.max_fraction > 0.0 && p.max_fraction <= 1.0) {
                    return bad(
                        &key("pack.max_fraction"),
                        format!("must be in (0, 1], got {}", p.max_fraction),
                    );
                }
                match self.bodies.iter().find(|o| o.name == p.into) {
                    Some(o) if matches!(o.mesh, MeshSpec::Container { .. }) => {
                        if o.rotate.is_some() || o.lattice.is_some() || o.pack.is_some() {
                            return bad(
                                &key("pack.into"),
                                format!("container `{}` must not be rotated or replicated", o.name),
                            );
                        }
                    }
                    Some(_) => {
                        return bad(
                            &key("pack.into"),
                            format!("body `{}` is not a mesh of kind `container`", p.into),
                        )
                    }
                    None => return bad(&key("pack.into"), format!("no body named `{}`", p.into)),
                }
            }
            if matches!(b.mesh, MeshSpec::Checkpoint { .. })
                && (b.pack.is_some() || b.lattice.is_some() || b.rotate.is_some())
            {
                return bad(
                    &key("mesh"),
                    "bodies from a checkpoint cannot be rotated, packed or replicated".into(),
                );
            }
            if let MeshSpec::Box {
                size,
                element_size,
                origin,
                ..
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
        if let Some(p) = &self.output.particles {
            if !self.bodies.iter().any(|b| b.name == p.template) {
                return bad(
                    "output.particles.template",
                    format!("no body entry named `{}`", p.template),
                );
            }
            if p.radial_bins == 0 {
                return bad("output.particles.radial_bins", "must be at least 1".into());
            }
        }
        if let Some(r) = self.mechanics.as_ref().map(|m| m.rebalance) {
            if !(r.threshold.is_finite() && r.threshold >= 1.0) {
                return bad(
                    "mechanics.rebalance.threshold",
                    format!("must be a number >= 1 (max/mean work), got {}", r.threshold),
                );
            }
        }
        if let Some(st) = self.mechanics.as_ref().and_then(|m| m.settle) {
            let ok = |v: Option<f64>| v.is_none_or(|x| x.is_finite() && x > 0.0);
            if st.kinetic_energy.is_none() && st.relative.is_none() && st.rms_speed.is_none() {
                return bad(
                    "mechanics.settle",
                    "give `kinetic_energy` (J), `relative` (of the peak) or `rms_speed` (m/s)"
                        .into(),
                );
            }
            if !ok(st.kinetic_energy)
                || !ok(st.relative)
                || !ok(st.rms_speed)
                || st.after.is_nan()
                || st.after < 0.0
            {
                return bad(
                    "mechanics.settle",
                    "thresholds must be positive and `after` >= 0".into(),
                );
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
                ..
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
        for (i, bc) in thermal.bc.iter().enumerate() {
            let key = |f: &str| format!("thermal.bc[{i}].{f}");
            match bc {
                ThermalBcSpec::Temperature { value, ramp, .. } => {
                    if !value.is_finite() {
                        return bad(&key("value"), "must be finite".into());
                    }
                    if let Some(r) = ramp {
                        if !(r.is_finite() && *r > 0.0) {
                            return bad(&key("ramp"), format!("must be positive (s), got {r}"));
                        }
                    }
                }
                ThermalBcSpec::Flux { value, .. } => {
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
        if let Some(m) = &self.mechanics {
            self.validate_mechanics(m)?;
        }
        self.validate_fracture()?;
        self.validate_particles()?;
        self.validate_spheres()?;
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
        self.validate_ambient()
    }

    /// Emissivities, the temperature offset and `thermal.ambient` (issue 20).
    fn validate_ambient(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        for (i, m) in self.materials.iter().enumerate() {
            if let Some(e) = m.emissivity {
                if !(e > 0.0 && e <= 1.0) {
                    return bad(
                        &format!("materials[{i}].emissivity"),
                        format!("must be in (0, 1], got {e} (material `{}`)", m.name),
                    );
                }
            }
        }
        let thermal = self.thermal_spec();
        let offset = thermal.temperature_offset;
        if !offset.is_finite() {
            return bad("thermal.temperature_offset", "must be finite".into());
        }
        if let Some(c) = &self.contact {
            let pairs = c.pair.iter().enumerate();
            let all = c.cmy.iter().map(|m| ("contact.cmy".to_string(), m));
            let each = pairs
                .filter_map(|(i, p)| Some((format!("contact.pair[{i}].cmy"), p.cmy.as_ref()?)));
            for (key, m) in all.chain(each) {
                m.check(&key).map_err(|e| (key.clone(), e))?;
                if m.pressure.is_none() && self.mechanics.is_none() {
                    return bad(
                        &format!("{key}.pressure"),
                        "a run without [mechanics] has no contact pressure: prescribe it (Pa)"
                            .into(),
                    );
                }
            }
        }
        if let Some(c) = &self.contact {
            let all = c.table.iter().map(|t| ("contact.table".to_string(), t));
            let each =
                c.pair.iter().enumerate().filter_map(|(i, p)| {
                    Some((format!("contact.pair[{i}].table"), p.table.as_ref()?))
                });
            for (key, t) in all.chain(each) {
                t.check(&key).map_err(|e| (key.clone(), e))?;
                if t.depends_on_pressure()
                    && t.prescribed_pressure.is_none()
                    && self.mechanics.is_none()
                {
                    return bad(
                        &format!("{key}.prescribed_pressure"),
                        "the table depends on pressure and a run without [mechanics] has no \
                         contact pressure: prescribe it (Pa)"
                            .into(),
                    );
                }
                if t.depends_on_temperature() && c.delta_t == crate::contact::DeltaT::Average {
                    return bad(
                        &format!("{key}.temperature"),
                        "a temperature-dependent conductance needs delta_t = \"local\"".into(),
                    );
                }
            }
            for (i, p) in c.pair.iter().enumerate() {
                let given = [p.resistance.is_some() || p.conductance.is_some()]
                    .into_iter()
                    .chain([p.cmy.is_some(), p.table.is_some()])
                    .filter(|&g| g)
                    .count();
                if given > 1 {
                    return bad(
                        &format!("contact.pair[{i}]"),
                        "give one of resistance/conductance, cmy or table".into(),
                    );
                }
            }
            if let Some(v) = c.sliding_speed.filter(|v| !(v.is_finite() && *v > 0.0)) {
                return bad(
                    "contact.sliding_speed",
                    format!("must be positive (m/s), got {v}"),
                );
            }
        }
        if let Some(f) = self.contact.as_ref().and_then(|c| c.friction_heating) {
            for (key, v) in [("fraction", f.fraction), ("weight", f.weight)] {
                if !(0.0..=1.0).contains(&v) {
                    return bad(
                        &format!("contact.friction_heating.{key}"),
                        format!("must be in [0, 1], got {v}"),
                    );
                }
            }
            if self.mechanics.as_ref().is_none_or(|m| m.contact.is_none()) {
                return bad(
                    "contact.friction_heating",
                    "needs the penalty contact's friction ([mechanics.contact])".into(),
                );
            }
        }
        let gap = self.contact.as_ref().and_then(|c| c.gap.as_ref());
        if let Some(g) = gap {
            if let Some(p) = g.pinball.filter(|p| !(p.is_finite() && *p > 0.0)) {
                return bad(
                    "contact.gap.pinball",
                    format!("must be positive (m), got {p}"),
                );
            }
            for (key, v) in [("conductivity", g.conductivity), ("h", g.h)] {
                if !(v.is_finite() && v >= 0.0) {
                    return bad(
                        &format!("contact.gap.{key}"),
                        format!("must be a non-negative number, got {v}"),
                    );
                }
            }
            if let Some(m) = g.min_gap.filter(|m| !(m.is_finite() && *m > 0.0)) {
                return bad(
                    "contact.gap.min_gap",
                    format!("must be positive (m), got {m}"),
                );
            }
            if let Some(k) = &g.conductivity_table {
                k.check("contact.gap.conductivity_table")
                    .map_err(|e| ("contact.gap.conductivity_table".to_string(), e))?;
            }
            if let Some(f) = &g.view_factor_table {
                let key = "contact.gap.view_factor_table";
                f.check(key).map_err(|e| (key.to_string(), e))?;
                if let Some(v) = f.y.iter().find(|v| !(**v > 0.0 && **v <= 1.0)) {
                    return bad(key, format!("values must be in (0, 1], got {v}"));
                }
            }
            if !(g.view_factor > 0.0 && g.view_factor <= 1.0) {
                return bad(
                    "contact.gap.view_factor",
                    format!("must be in (0, 1], got {}", g.view_factor),
                );
            }
        }
        let gap_radiation = gap.is_some_and(|g| g.radiation);
        let Some(a) = thermal.ambient.clone().or_else(|| {
            gap_radiation.then(|| AmbientSpec {
                temperature: -offset,
                h: 0.0,
                radiation: false,
                bodies: Vec::new(),
            })
        }) else {
            return Ok(());
        };
        let a = &a;
        if !self.has_thermal() {
            return bad(
                "thermal.ambient",
                "needs the thermal problem (a [thermal] table)".into(),
            );
        }
        if !a.temperature.is_finite() {
            return bad("thermal.ambient.temperature", "must be finite".into());
        }
        if !(a.h.is_finite() && a.h >= 0.0) {
            return bad(
                "thermal.ambient.h",
                format!("must be a non-negative number (W/m^2/K), got {}", a.h),
            );
        }
        for (i, name) in a.bodies.iter().enumerate() {
            if !self.bodies.iter().any(|b| &b.name == name) {
                return bad(
                    &format!("thermal.ambient.bodies[{i}]"),
                    format!("no body named `{name}`"),
                );
            }
        }
        if !(a.radiation || gap_radiation) {
            return Ok(());
        }
        let key = if a.radiation {
            "thermal.ambient.radiation"
        } else {
            "contact.gap.radiation"
        };
        let exposed =
            |b: &BodySpec| gap_radiation || a.bodies.is_empty() || a.bodies.contains(&b.name);
        for b in self.bodies.iter().filter(|b| exposed(b)) {
            let mats = std::iter::once(&b.material).chain(b.regions.values());
            for name in mats {
                let i = self.materials.iter().position(|m| &m.name == name);
                if let Some(i) = i.filter(|&i| self.materials[i].emissivity.is_none()) {
                    return bad(
                        &format!("materials[{i}].emissivity"),
                        format!(
                            "missing (material `{name}` of body `{}`): {key} needs it",
                            b.name
                        ),
                    );
                }
            }
        }
        // Radiation needs absolute temperatures: none may lie below -offset.
        let mut temps: Vec<(String, f64)> =
            vec![("thermal.ambient.temperature".into(), a.temperature)];
        for (i, b) in self.bodies.iter().enumerate() {
            temps.push((
                format!("bodies[{i}].initial_temperature"),
                b.initial_temperature,
            ));
        }
        for (i, init) in thermal.initial.iter().enumerate() {
            temps.push((format!("thermal.initial[{i}].value"), init.value));
        }
        for (i, bc) in thermal.bc.iter().enumerate() {
            match bc {
                ThermalBcSpec::Temperature { value, .. } => {
                    temps.push((format!("thermal.bc[{i}].value"), *value))
                }
                ThermalBcSpec::Convection { ambient, .. } => {
                    temps.push((format!("thermal.bc[{i}].ambient"), *ambient))
                }
                _ => {}
            }
        }
        if let Some((key, t)) = temps.into_iter().find(|(_, t)| t + offset < 0.0) {
            return bad(
                "thermal.temperature_offset",
                format!(
                    "{key} = {t} is below absolute zero with thermal.temperature_offset = \
                     {offset}; radiation needs absolute temperatures (273.15 for degrees \
                     Celsius, 0 for kelvin)"
                ),
            );
        }
        Ok(())
    }

    /// The bodies' `fracture` tables and their materials' fracture keys.
    fn validate_fracture(&self) -> Result<(), (String, String)> {
        for (i, b) in self.bodies.iter().enumerate() {
            let Some(f) = &b.fracture else { continue };
            let key = |k: &str| format!("bodies[{i}].fracture{k}");
            if self.mechanics.is_none() {
                return Err((key(""), "joints need a [mechanics] table".into()));
            }
            if matches!(b.mesh, MeshSpec::Checkpoint { .. }) {
                // A checkpoint body has no named sets, and one plane would
                // miss most of the bodies of a packing.
                if f.set.is_some() {
                    return Err((
                        key(".set"),
                        "bodies from a checkpoint are jointed whole: they have no element sets"
                            .into(),
                    ));
                }
                if f.initial_crack.is_some() {
                    return Err((
                        key(".initial_crack"),
                        "not for bodies from a checkpoint (they are jointed whole, uncracked)"
                            .into(),
                    ));
                }
            }
            if let Some(c) = &f.initial_crack {
                if !c.point.iter().all(|x| x.is_finite()) {
                    return Err((
                        key(".initial_crack.point"),
                        format!("must be finite, got {:?}", c.point),
                    ));
                }
                let len2: f64 = c.normal.iter().map(|x| x * x).sum();
                if !(len2.is_finite() && len2 > 0.0) {
                    return Err((
                        key(".initial_crack.normal"),
                        format!("must be finite and non-zero, got {:?}", c.normal),
                    ));
                }
            }
            let name = f.material.as_deref().unwrap_or(&b.material);
            let Some(m) = self.materials.iter().position(|m| m.name == name) else {
                return Err((key(".material"), format!("no material named `{name}`")));
            };
            match self.materials[m].fracture() {
                Ok(Some(_)) => {}
                Ok(None) => {
                    return Err((
                        format!("materials[{m}]"),
                        format!(
                            "material `{name}` has no fracture keys (tensile_strength, \
                             cohesion, friction_angle, g_i, g_ii, fracture_penalty)"
                        ),
                    ))
                }
                Err((k, msg)) => return Err((format!("materials[{m}].{k}"), msg)),
            }
        }
        for (m, mat) in self.materials.iter().enumerate() {
            if let Err((k, msg)) = mat.fracture() {
                return Err((format!("materials[{m}].{k}"), msg));
            }
        }
        Ok(())
    }

    /// The bodies' `particles` tables (issue 21): what the model cannot
    /// check without the mesh (the set, the radius against it) it checks.
    fn validate_particles(&self) -> Result<(), (String, String)> {
        for (i, b) in self.bodies.iter().enumerate() {
            let Some(p) = &b.particles else { continue };
            let key = |k: &str| format!("bodies[{i}].particles{k}");
            let refuse = |why: &str| Err((key(""), format!("body `{}`: {why}", b.name)));
            if !(p.radius.is_finite() && p.radius > 0.0) {
                return Err((
                    key(".radius"),
                    format!("must be positive, got {}", p.radius),
                ));
            }
            if matches!(b.mesh, MeshSpec::Checkpoint { .. }) {
                return refuse("a body from a checkpoint has no element sets");
            }
            if b.lattice.is_some() || b.pack.is_some() {
                return refuse(
                    "particles are for a body of its own mesh, not lattice or pack copies",
                );
            }
            if b.fracture.is_some() {
                return refuse("a body with particles cannot have joints (fracture) too");
            }
            if b.fixed || b.velocity.is_some() {
                return refuse("a held body (fixed, velocity) cannot have particles");
            }
        }
        Ok(())
    }

    fn validate_mechanics(&self, m: &MechanicsSpec) -> Result<(), (String, String)> {
        let bad = |k: &str, msg: String| Err((k.to_string(), msg));
        let used: Vec<&str> = self
            .bodies
            .iter()
            .flat_map(|b| {
                std::iter::once(b.material.as_str()).chain(b.regions.values().map(String::as_str))
            })
            .collect();
        for (i, mat) in self.materials.iter().enumerate() {
            if !used.contains(&mat.name.as_str()) {
                continue;
            }
            let key = |f: &str| format!("materials[{i}].{f}");
            match (mat.young, mat.poisson) {
                (Some(e), Some(nu)) => {
                    if !(e.is_finite() && e > 0.0) {
                        return bad(&key("young"), format!("must be positive, got {e}"));
                    }
                    if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                        return bad(&key("poisson"), format!("must be in (-1, 0.5), got {nu}"));
                    }
                }
                _ => {
                    return bad(
                        &key("young"),
                        format!(
                            "material `{}` needs `young` and `poisson` for the mechanics",
                            mat.name
                        ),
                    )
                }
            }
            if !mat.expansion.is_finite() {
                return bad(&key("expansion"), "must be finite".into());
            }
            if !(mat.viscosity.is_finite() && mat.viscosity >= 0.0) {
                return bad(&key("viscosity"), "must be non-negative".into());
            }
        }
        if let Some(dt) = m.dt {
            if !(dt.is_finite() && dt > 0.0) {
                return bad("mechanics.dt", format!("must be positive, got {dt}"));
            }
        }
        if !(m.safety > 0.0 && m.safety <= 1.0) {
            return bad(
                "mechanics.safety",
                format!("must be in (0, 1], got {}", m.safety),
            );
        }
        if m.substeps == Some(0) {
            return bad("mechanics.substeps", "must be at least 1".into());
        }
        if m.gravity.iter().any(|g| !g.is_finite()) {
            return bad("mechanics.gravity", "must be finite".into());
        }
        if !(m.damping.is_finite() && m.damping >= 0.0) {
            return bad("mechanics.damping", "must be non-negative".into());
        }
        if let Some(c) = m.free_damping {
            if !(c.is_finite() && c >= 0.0) {
                return bad("mechanics.free_damping", "must be non-negative".into());
            }
            if m.contact.is_none() {
                return bad(
                    "mechanics.free_damping",
                    "needs [mechanics.contact]: without contact every body is in free flight"
                        .into(),
                );
            }
        }
        for (i, bc) in m.bc.iter().enumerate() {
            let key = format!("mechanics.bc[{i}]");
            match bc {
                MechanicsBcSpec::Fixed {
                    components: Some(c),
                    ..
                } => {
                    if c.is_empty() || c.iter().any(|x| !["x", "y", "z"].contains(&x.as_str())) {
                        return bad(
                            &format!("{key}.components"),
                            format!("must list some of \"x\", \"y\", \"z\", got {c:?}"),
                        );
                    }
                }
                MechanicsBcSpec::Fixed { .. } => {}
                MechanicsBcSpec::Velocity { value, .. } => {
                    if value.iter().any(|x| x.is_infinite()) {
                        return bad(&format!("{key}.value"), "must be finite (NaN: free)".into());
                    }
                }
                MechanicsBcSpec::Traction { value, .. } => {
                    if value.iter().any(|x| !x.is_finite()) {
                        return bad(&format!("{key}.value"), "must be finite".into());
                    }
                }
            }
        }
        if let Some(c) = &m.contact {
            for (f, v, min) in [
                ("penalty", c.penalty, f64::MIN_POSITIVE),
                ("friction", c.friction, 0.0),
                ("damping_ratio", c.damping_ratio, 0.0),
                ("slip_velocity", c.slip_velocity, f64::MIN_POSITIVE),
                ("linear_tolerance", c.linear_tolerance, 0.0),
            ] {
                if !(v.is_finite() && v >= min) {
                    return bad(
                        &format!("mechanics.contact.{f}"),
                        format!(
                            "must be {}, got {v}",
                            if min > 0.0 {
                                "positive"
                            } else {
                                "non-negative"
                            }
                        ),
                    );
                }
            }
            if !(c.stick_limit.is_finite() && c.stick_limit >= 1.0) {
                return bad(
                    "mechanics.contact.stick_limit",
                    format!(
                        "must be at least 1 (one pair's explicit stick limit), got {}",
                        c.stick_limit
                    ),
                );
            }
            // k_t ≤ k_n keeps the explicit step of the normal spring stable for the tangential one.
            let kt = c.tangential_stiffness;
            if !(kt.is_finite() && (0.0..=1.0).contains(&kt)) {
                return bad(
                    "mechanics.contact.tangential_stiffness",
                    format!("must be a fraction of the normal stiffness in [0, 1], got {kt}"),
                );
            }
            if let Some(g) = c.margin {
                if !(g.is_finite() && g > 0.0) {
                    return bad(
                        "mechanics.contact.margin",
                        format!("must be positive, got {g}"),
                    );
                }
            }
        }
        Ok(())
    }
}

impl MaterialSpec {
    /// The fracture constants, when any fracture key is given: all six
    /// are then needed; errors are (key, message).
    pub fn fracture(
        &self,
    ) -> Result<Option<crate::fracture::law::FractureMaterial>, (String, String)> {
        let keys = [
            ("tensile_strength", self.tensile_strength),
            ("cohesion", self.cohesion),
            ("friction_angle", self.friction_angle),
            ("g_i", self.g_i),
            ("g_ii", self.g_ii),
            ("fracture_penalty", self.fracture_penalty),
        ];
        if keys.iter().all(|(_, v)| v.is_none()) && self.bk_exponent.is_none() {
            return Ok(None);
        }
        let mut v = [0.0; 6];
        for (slot, (k, value)) in v.iter_mut().zip(keys) {
            *slot = value.ok_or_else(|| {
                (
                    k.to_string(),
                    format!(
                        "missing (material `{}`): a fracture material needs tensile_strength, \
                         cohesion, friction_angle, g_i, g_ii and fracture_penalty",
                        self.name
                    ),
                )
            })?;
        }
        let m = crate::fracture::law::FractureMaterial {
            tensile_strength: v[0],
            cohesion: v[1],
            friction_angle: v[2].to_radians(),
            g_i: v[3],
            g_ii: v[4],
            penalty: v[5],
            bk_exponent: self.bk_exponent.unwrap_or(1.0),
        };
        m.validate().map_err(|msg| {
            // The law names the key between backquotes.
            let k = msg.split('`').nth(1).unwrap_or("fracture").to_string();
            (k, msg)
        })?;
        Ok(Some(m))
    }
}
