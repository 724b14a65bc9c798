//! The theta integrator on PETSc (seed 000 eq 22).
//!
//! With M Ṫ + K T = f (K including convection), eq 22 gives
//! (M/Δt + θK) Tⁿ⁺¹ = (M/Δt − (1−θ)K) Tⁿ + f.
//! Dirichlet rows are eliminated symmetrically: A = M/Δt + θK has those
//! rows and columns replaced by the identity, the lifting −A_fd T_d goes
//! into a constant vector g, and B = M/Δt − (1−θ)K has those rows zeroed,
//! so every step is one `MatMultAdd` and one `KSPSolve`:
//!   rhs = B Tⁿ + g,  A Tⁿ⁺¹ = rhs.
//! A and B are assembled once; the KSP keeps its preconditioner or
//! factorisation for the whole run. θ = 0 with lumped capacity is the
//! explicit scheme of eq 23, Tⁿ⁺¹ = E Tⁿ + g with E = I − Δt M_L⁻¹ K:
//! one `MatMultAdd` per step and no solve.
//!
//! Energy account: summing the equations over all rows and steps, with
//! reactions r on the Dirichlet rows,
//!   Σ_i [M (T_N − T_0)]_i = t Σ f − Δt 1ᵀ K S + Δt Σ_n Σ_d rⁿ_d,
//! where S = Σ_n (θTⁿ⁺¹ + (1−θ)Tⁿ); conductivity rows sum to zero, so
//! 1ᵀ K S is the convection loss. [`ThermalSystem::energy`] evaluates the
//! boundary heat from the Dirichlet rows of the unconstrained operators
//! and the stored heat from M, so the two agree to solver tolerance.
//!
//! A prescribed temperature with a ramp goes linearly from the node's
//! initial temperature to its value over the ramp's seconds: while any
//! ramps, each step evaluates the prescribed values T_d(tⁿ⁺¹) and the
//! lifting g again from the unconstrained A (one more `MatMult`); the
//! explicit scheme sets its prescribed rows to them after the update.

use crate::contact::{ContactSet, DeltaT};
use crate::model::Model;
use crate::parallel::Part;
use crate::petsc::{Ksp, Matrix, Petsc, Result, Snes, Vector};
use crate::scenario::{CapacityKind, SolverSpec};
use mpi::topology::SimpleCommunicator;

use super::assembly::{assemble, Operators};
use super::exchange::Exchange;
use super::nonlinear::{radiated, GapRadiation, RadiatingStep};
use super::solver_choice::initial_guess;
#[path = "sphere_source.rs"]
mod sphere_source;

/// Krylov iterations per Newton iteration above which a radiating step's
/// preconditioner is rebuilt at the next Jacobian (it is kept otherwise;
/// `-snes_lag_preconditioner` sets a fixed lag instead).
const REBUILD_ITERATIONS: i32 = 30;

/// What one step did.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepStats {
    /// Krylov iterations (0 for the explicit scheme).
    pub iterations: i32,
    /// Newton iterations (0 for a linear step).
    pub newton: i32,
}

/// Heat balance since the start (J, or the user's energy unit).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergyAccount {
    /// Stored heat now, Σ (M T)_i.
    pub stored: f64,
    /// Change of stored heat since t = 0.
    pub stored_change: f64,
    /// Heat in through prescribed-temperature nodes.
    pub dirichlet_in: f64,
    /// Heat in through fluxes and sources.
    pub flux_in: f64,
    /// Heat in by convection (negative when the body cools).
    pub convection_in: f64,
    /// Heat in by radiation from the ambient (negative when it cools).
    pub radiation_in: f64,
    /// Heat made by friction (issue 20).
    pub friction_in: f64,
}

impl EnergyAccount {
    /// Total heat in through the boundary (and sources).
    pub fn boundary_in(&self) -> f64 {
        self.dirichlet_in + self.flux_in + self.convection_in + self.radiation_in + self.friction_in
    }
}

/// The heat account's running state since the last assembly (owned rows,
/// PETSc order): a checkpoint saves it so that a restart continues the
/// account exactly, not only to round-off.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AccountState {
    /// The account carried over from before the last assembly.
    pub base: EnergyAccount,
    /// Temperatures at the last assembly.
    pub t0: Vec<f64>,
    /// Sum of the temperatures of the steps since then.
    pub t_sum: Vec<f64>,
    /// Steps since then.
    pub steps: u64,
    /// The radiated heat per row since then (empty without radiation).
    pub rad_sum: Vec<f64>,
}

enum Scheme<'p> {
    Explicit {
        e: Matrix<'p>,
        g: Vector<'p>,
        /// Δt / m_i on free rows, 0 on prescribed ones.
        dt_minv: Vector<'p>,
    },
    Implicit {
        /// The system matrix; the KSP factorises it once.
        _a: Matrix<'p>,
        b: Matrix<'p>,
        /// B's diagonal when B is diagonal (θ = 1, lumped capacity): the
        /// right-hand side is then a pointwise product, not a product with
        /// a matrix of the stiffness's pattern (72 us of a 680 us step on
        /// the seed's slab at 6,561 unknowns).
        b_diag: Option<Vector<'p>>,
        g: Vector<'p>,
        rhs: Vector<'p>,
        ksp: Box<Ksp<'p>>,
        /// Fischer's space is to be seeded with Tⁿ before the next solve.
        seed: bool,
    },
    /// The implicit step with radiation: Newton on A T + θ R(T) = rhs.
    Newton {
        b: Matrix<'p>,
        g: Vector<'p>,
        snes: Box<Snes<'p, RadiatingStep<'p>>>,
    },
}

/// Radiation's state: the coefficients, R at the step's start and end,
/// and the radiated heat per row since the last assembly (the account).
struct Radiating<'p> {
    /// ε σ a_free on every row.
    coef: Vector<'p>,
    /// The gap links' Laplacian, when gaps radiate.
    gap: Option<Matrix<'p>>,
    /// Room for the fourth powers.
    u: Vector<'p>,
    offset: f64,
    ambient4: f64,
    r0: Vector<'p>,
    r1: Vector<'p>,
    /// Σ Δt (θ R(Tⁿ⁺¹) + (1 − θ) R(Tⁿ)) per row.
    sum: Vector<'p>,
    /// Contact and gap heat with temperature-dependent conductance: part
    /// of R here (it sums to zero over the rows).
    exchange: Option<Exchange<'p>>,
}

/// Prescribed temperatures that ramp: per owned row, the start and end
/// values and the ramp's duration (0: not ramped), and what the lifting
/// needs to be evaluated again.
struct Ramp<'p> {
    start: Vec<f64>,
    end: Vec<f64>,
    time: Vec<f64>,
    /// The longest ramp (s).
    until: f64,
    /// The unconstrained A (implicit scheme only), the load on free rows,
    /// the free rows' mask, and room for the prescribed values.
    a0: Option<Matrix<'p>>,
    f_free: Vector<'p>,
    free_mask: Vector<'p>,
    xd: Vector<'p>,
}

impl Radiating<'_> {
    /// The radiated power R(x) into r0 (the step's start) or r1 (its end).
    fn power(&mut self, x: &Vector, end: bool) -> Result<()> {
        let out = if end { &mut self.r1 } else { &mut self.r0 };
        let (c, g, o, a4) = (&self.coef, self.gap.as_ref(), self.offset, self.ambient4);
        radiated(c, g, x, o, a4, &mut self.u, out)?;
        if let Some(ex) = self.exchange.as_mut() {
            ex.add_heat(x, out, false)?;
        }
        Ok(())
    }
}

/// The assembled thermal problem and its state.
pub struct ThermalSystem<'p> {
    ops: Operators<'p>,
    scheme: Scheme<'p>,
    /// Temperatures of the owned PETSc rows (one per owned node, in their
    /// order, unless intact joints tie copies of nodes to one row: see
    /// [`Self::node_temperatures`]).
    pub t: Vector<'p>,
    t_next: Vector<'p>,
    t0: Vector<'p>,
    t_sum: Vector<'p>,
    dmask: Vector<'p>,
    work: Vector<'p>,
    theta: f64,
    dt: f64,
    steps: u64,
    steps_total: u64,
    warm_start: bool,
    /// `t_next` holds the step before `t`: the warm start extrapolates.
    extrapolate: bool,
    /// Heat balance carried over from before the last rebuild.
    base: EnergyAccount,
    /// Times the operator was assembled (1 + rebuilds after contact changes).
    pub assemblies: u64,
    /// Total Krylov iterations so far.
    pub iterations: u64,
    /// The solver in use ("cg/gamg", "explicit", ...).
    pub solver_name: String,
    /// Ramped prescribed temperatures, while any ramps.
    ramp: Option<Ramp<'p>>,
    /// Free-surface radiation (issue 20).
    rad: Option<Radiating<'p>>,
    /// Frictional heat handed over by the mechanics for the next step (J
    /// per row), when frictional heating is on (issue 20).
    friction: Option<Vector<'p>>,
    /// The free spheres' heat in `friction`, pending and released (issue 21).
    spheres: sphere_source::SphereSource,
    /// Total Newton iterations so far (radiating runs).
    pub newton_iterations: u64,
    /// Newton's absolute tolerance as a fraction of ‖rhs‖ (the linear rtol).
    newton_rtol: f64,
    /// The gathering of the contact rows' temperatures for the history's
    /// flows, with the fingerprint of the rows it was made for.
    flow_gather: Option<(u64, crate::petsc::Gather<'p>)>,
}

impl<'p> ThermalSystem<'p> {
    /// Collective. Assemble, apply Dirichlet conditions and set up the solver.
    pub fn new(
        petsc: &'p Petsc,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        solver: &SolverSpec,
        contacts: &ContactSet,
    ) -> crate::error::Result<Self> {
        let mut ops = assemble(petsc, comm, model, part, contacts)?;
        let mut radiation = ops.radiation.take();
        let exchange = ops.exchange.take();
        if exchange.is_some() && radiation.is_none() {
            // Temperature-dependent contact conductance alone: the Newton
            // step with nothing radiated.
            let mut coef = Vector::new(petsc, part.owned_rows())?;
            coef.set(0.0)?;
            radiation = Some(super::assembly::Radiation {
                coef,
                gap: None,
                offset: model.thermal.offset,
                ambient4: 0.0,
            });
        }
        let gap_radiates = radiation.as_ref().is_some_and(|r| r.gap.is_some());
        // g'(T̄) (Λ T) mᵀ of a temperature-dependent conductance is not symmetric.
        let symmetric = !gap_radiates
            && exchange.is_none()
            && model
                .contact
                .as_ref()
                .is_none_or(|c| c.delta_t == DeltaT::Local || contacts.total_pairs == 0);
        let theta = model.thermal.theta;
        let dt = model.dt;
        let owned = part.owned_rows();
        let (lo, _) = part.owned_range();

        let mut t = Vector::new(petsc, owned)?;
        let ramp_of = |k: usize| part.bc.dirichlet_ramp.get(k).copied().unwrap_or(0.0);
        // The prescribed values at the end of any ramp (the lifting's), and
        // the ramped rows' start values, ends and durations.
        let mut t_end = t.duplicate()?;
        let mut ramped: Vec<(usize, f64, f64, f64)> = Vec::new();
        {
            let start = super::particles::initial_rows(model, part);
            let mut v = t.view_mut()?;
            v.copy_from_slice(&start);
            let mut e = t_end.view_mut()?;
            e.copy_from_slice(&start);
            for (k, &(l, value)) in part.bc.dirichlet.iter().enumerate() {
                // A copy whose row is another rank's: that rank prescribes it.
                let Some(r) = (part.petsc[l as usize] as usize).checked_sub(lo) else {
                    continue;
                };
                if r >= owned {
                    continue;
                }
                e[r] = value;
                match ramp_of(k) {
                    0.0 => v[r] = value,
                    secs => ramped.push((r, start[r], value, secs)),
                }
            }
        }
        // One row per prescribed node (the copies of a jointed node share one).
        let mut d_rows: Vec<i32> = part
            .bc
            .dirichlet
            .iter()
            .map(|&(l, _)| part.petsc[l as usize] as i32)
            .filter(|&r| (lo..lo + owned).contains(&(r as usize)))
            .collect();
        d_rows.sort_unstable();
        d_rows.dedup();
        let mut dmask = t.duplicate()?;
        dmask.set(0.0)?;
        {
            let mut v = dmask.view_mut()?;
            for &r in &d_rows {
                v[r as usize - lo] = 1.0;
            }
        }
        let mut free_mask = t.duplicate()?;
        free_mask.set(1.0)?;
        free_mask.axpy(-1.0, &dmask)?;
        // xd: the prescribed values on Dirichlet rows (at the end of any
        // ramp), zero elsewhere.
        let mut xd = t.duplicate()?;
        xd.pointwise_mult(&t_end, &dmask)?;
        // Whether any rank has a ramp, and the longest: the lifting's
        // re-evaluation is collective, so every rank takes part (a rank
        // without ramped rows would otherwise skip the MatDuplicate and
        // the products the others wait in).
        let (any_ramp, ramp_until) = {
            let mine = [
                f64::from(u8::from(!ramped.is_empty())),
                ramped.iter().map(|r| r.3).fold(0.0, f64::max),
            ];
            let mut all = [0.0; 2];
            mpi::traits::CommunicatorCollectives::all_reduce_into(
                comm,
                &mine[..],
                &mut all[..],
                mpi::collective::SystemOperation::max(),
            );
            (all[0] > 0.0, all[1])
        };
        let ramp_a0 = any_ramp;
        let mut f_free = t.duplicate()?;
        f_free.pointwise_mult(&ops.load, &free_mask)?;

        super::limits::check_time_step(petsc, model, &ops, &free_mask)?;

        let explicit = theta == 0.0 && model.thermal.capacity == CapacityKind::Lumped;
        let mut warm_start = false;
        let (scheme, solver_name, a0) = if explicit {
            // Seed 000 eq 23: Tⁿ⁺¹ = Tⁿ + Δt M_L⁻¹ (f − K Tⁿ).
            let mut dt_minv = t.duplicate()?;
            {
                let ms = ops.capacity_rowsum.view()?;
                let mut v = dt_minv.view_mut()?;
                for i in 0..v.len() {
                    v[i] = dt / ms[i];
                }
            }
            dt_minv.pointwise_mult(&dt_minv.duplicate_from()?, &free_mask)?;
            let mut e = ops.stiffness.duplicate()?;
            e.scale(-1.0)?;
            e.diagonal_scale(Some(&dt_minv), None)?;
            e.shift(1.0)?;
            let mut g = t.duplicate()?;
            g.pointwise_mult(&ops.load, &dt_minv)?;
            (
                Scheme::Explicit { e, g, dt_minv },
                "explicit (lumped, no solve)".to_string(),
                None,
            )
        } else {
            let mut a = ops.capacity.duplicate()?;
            a.scale(1.0 / dt)?;
            if theta != 0.0 {
                a.axpy_same_pattern(theta, &ops.stiffness)?;
            }
            // The unconstrained A, kept to evaluate the lifting while a ramp runs.
            let a0 = if ramp_a0 { Some(a.duplicate()?) } else { None };
            let mut b = ops.capacity.duplicate()?;
            b.scale(1.0 / dt)?;
            if theta != 1.0 {
                b.axpy_same_pattern(-(1.0 - theta), &ops.stiffness)?;
            }
            // g = f_free − A xd on free rows, T_d on Dirichlet rows.
            let mut g = t.duplicate()?;
            a.mult(&xd, &mut g)?;
            g.scale(-1.0)?;
            g.pointwise_mult(&g.duplicate_from()?, &free_mask)?;
            g.axpy(1.0, &f_free)?;
            g.axpy(1.0, &xd)?;
            a.zero_rows_columns(&d_rows, 1.0)?;
            b.zero_rows(&d_rows, 0.0)?;
            if symmetric {
                a.set_symmetric(true)?;
            }

            let fourier = super::solver_choice::cell_fourier(&ops, &free_mask, theta * dt)?;
            let choice =
                super::SolverChoice::auto(part.num_global(), part.size, symmetric, fourier);
            let (choice, ordering) = choice.configure(petsc, &solver.options, &a)?;
            if let Some(rad) = radiation.as_ref() {
                let mut coef_free = rad.coef.duplicate()?;
                coef_free.pointwise_mult(&rad.coef, &free_mask)?;
                let j = a.duplicate()?;
                let gap = match rad.gap.as_ref() {
                    None => None,
                    Some(lap) => Some(GapRadiation {
                        lap: lap.duplicate()?,
                        free: free_mask.duplicate_from()?,
                        scaled: lap.duplicate()?,
                        u: t.duplicate()?,
                        lu: t.duplicate()?,
                    }),
                };
                let ex = match exchange.as_ref() {
                    None => None,
                    Some((units, laws)) => Some((
                        Exchange::new(units.clone(), laws.clone(), &t, &ops.capacity)?,
                        free_mask.duplicate_from()?,
                    )),
                };
                let step = RadiatingStep {
                    gap,
                    exchange: ex,
                    rhs: t.duplicate()?,
                    work: t.duplicate()?,
                    a,
                    coef_free,
                    theta,
                    offset: rad.offset,
                    ambient4: rad.ambient4,
                    symmetric,
                };
                let mut snes = Box::new(Snes::new(petsc, step, t.duplicate()?, j)?);
                // The Jacobian changes with T at every Newton iteration, but
                // little: its preconditioner (a factorisation by default) is
                // kept, and a Krylov solver closes the gap, until the solves
                // need more than REBUILD_ITERATIONS per Newton iteration;
                // a direct solve would factorise at every iteration (7.3 s
                // against 32 ms per step on the 500-nut lattice, measured).
                let krylov = if symmetric { "cg" } else { "gmres" };
                let kt = match choice.ksp_type.as_str() {
                    "preonly" => krylov,
                    other => other,
                };
                snes.set_linear(
                    solver.ksp_type.as_deref().unwrap_or(kt),
                    solver.pc_type.as_deref().unwrap_or(&choice.pc_type),
                    solver.rtol.unwrap_or(1e-10),
                    solver.atol.unwrap_or(1e-50),
                )?;
                snes.set_lag_preconditioner(-2)?;
                // Newton to 1e-10 of the first residual, or a step below
                // 1e-12 of the temperatures (round-off near a steady state).
                snes.set_tolerances(1e-300, 1e-10, 1e-12, 50)?;
                snes.set_from_options()?;
                let name = format!("{} (cell Fourier number {fourier:.3})", snes.types()?);
                (Scheme::Newton { b, g, snes }, name, a0)
            } else {
                let mut ksp = Box::new(Ksp::new(petsc)?);
                ksp.set_operator(&a)?;
                ksp.set_types(
                    solver.ksp_type.as_deref().unwrap_or(&choice.ksp_type),
                    solver.pc_type.as_deref().unwrap_or(&choice.pc_type),
                )?;
                ksp.set_tolerances(
                    solver.rtol.unwrap_or(1e-10),
                    solver.atol.unwrap_or(1e-50),
                    solver.max_it.unwrap_or(10_000) as i32,
                )?;
                ksp.set_from_options()?;
                let (kt, pt) = ksp.types()?;
                if kt == "cg" && pt == "jacobi" && !petsc.has_option("ksp_norm_type")? {
                    ksp.set_natural_norm()?;
                }
                // Where an iterative solve starts (a direct one ignores it).
                let (w, seed, guess) = initial_guess(petsc, &mut ksp, &kt, fourier, solver.guess)?;
                warm_start = w;
                ksp.set_up()?;
                let rhs = t.duplicate()?;
                let b_diag = if theta == 1.0 && model.thermal.capacity == CapacityKind::Lumped {
                    let mut d = t.duplicate()?;
                    d.pointwise_mult(&ops.capacity_rowsum, &free_mask)?;
                    d.scale(1.0 / dt)?;
                    Some(d)
                } else {
                    None
                };
                (
                    Scheme::Implicit {
                        _a: a,
                        b,
                        b_diag,
                        g,
                        rhs,
                        ksp,
                        seed,
                    },
                    match ordering.filter(|_| pt == "cholesky") {
                        Some(o) => {
                            format!("{kt}/{pt} ({o} ordering; cell Fourier number {fourier:.3})")
                        }
                        None => format!("{kt}/{pt} (cell Fourier number {fourier:.3}{guess})"),
                    },
                    a0,
                )
            }
        };
        let rad = match radiation {
            None => None,
            Some(r) => {
                let mut sum = t.duplicate()?;
                sum.set(0.0)?;
                let exchange = match exchange {
                    None => None,
                    Some((units, laws)) => Some(Exchange::new(units, laws, &t, &ops.capacity)?),
                };
                Some(Radiating {
                    exchange,
                    u: t.duplicate()?,
                    gap: r.gap,
                    offset: r.offset,
                    ambient4: r.ambient4,
                    r0: t.duplicate()?,
                    r1: t.duplicate()?,
                    sum,
                    coef: r.coef,
                })
            }
        };

        let ramp = if !any_ramp {
            None
        } else {
            let n = t.view()?.len();
            let (mut start, mut end, mut time) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            {
                let e = t_end.view()?;
                end.copy_from_slice(&e);
            }
            for &(r, s0, _, secs) in &ramped {
                start[r] = s0;
                time[r] = secs;
            }
            let mut f = f_free.duplicate()?;
            f.copy_from(&f_free)?;
            let mut m = free_mask.duplicate()?;
            m.copy_from(&free_mask)?;
            Some(Ramp {
                until: ramp_until,
                start,
                end,
                time,
                a0,
                f_free: f,
                free_mask: m,
                xd: t.duplicate()?,
            })
        };
        let mut t0 = t.duplicate()?;
        t0.copy_from(&t)?;
        let mut t_sum = t.duplicate()?;
        t_sum.set(0.0)?;
        let t_next = t.duplicate()?;
        let work = t.duplicate()?;
        // Heat handed over: friction's (issue 20), the free spheres' (issue 21).
        let handed = model.contact.as_ref().and_then(|c| c.friction_heating);
        let mut friction = None;
        if handed.is_some() || !model.spheres.is_empty() {
            friction.insert(t.duplicate()?).set(0.0)?;
        }
        Ok(ThermalSystem {
            ops,
            scheme,
            t,
            t_next,
            t0,
            t_sum,
            dmask,
            work,
            theta,
            dt,
            warm_start,
            extrapolate: false,
            base: EnergyAccount::default(),
            assemblies: 1,
            steps: 0,
            steps_total: 0,
            iterations: 0,
            solver_name,
            ramp,
            rad,
            friction,
            spheres: Default::default(),
            newton_iterations: 0,
            newton_rtol: solver.rtol.unwrap_or(1e-10),
            flow_gather: None,
        })
    }

    /// Collective. Advance one time step.
    #[inline]
    pub fn step(&mut self) -> Result<StepStats> {
        // Ramped prescribed values at the step's end, while they ramp.
        let time = (self.steps_total + 1) as f64 * self.dt;
        let ramping = match &mut self.ramp {
            Some(r) if time - self.dt < r.until => {
                {
                    let mut v = r.xd.view_mut()?;
                    for (i, x) in v.iter_mut().enumerate() {
                        // Ramped rows: linear from the start to the end value.
                        *x = if r.time[i] > 0.0 {
                            let s = (time / r.time[i]).min(1.0);
                            r.start[i] + (r.end[i] - r.start[i]) * s
                        } else {
                            r.end[i]
                        };
                    }
                }
                // Zero on free rows: keep the prescribed rows only.
                r.xd.pointwise_mult(&r.xd.duplicate_from()?, &self.dmask)?;
                let g = match &mut self.scheme {
                    Scheme::Implicit { g, .. } | Scheme::Newton { g, .. } => Some(g),
                    Scheme::Explicit { .. } => None,
                };
                if let (Some(a0), Some(g)) = (&r.a0, g) {
                    // g = f_free − free ∘ (A xd) + xd.
                    a0.mult(&r.xd, g)?;
                    g.scale(-1.0)?;
                    g.pointwise_mult(&g.duplicate_from()?, &r.free_mask)?;
                    g.axpy(1.0, &r.f_free)?;
                    g.axpy(1.0, &r.xd)?;
                }
                true
            }
            _ => false,
        };
        // Frictional heat handed over: a source over the step on free rows;
        // on prescribed rows the reservoir takes it.
        let mut friction = None;
        if let Some(f) = self.friction.as_mut() {
            let (total, on_d) = (f.sum()?, f.dot(&self.dmask)?);
            // The spheres' part is theirs, not friction's.
            self.base.friction_in += total - self.spheres.release();
            self.base.dirichlet_in -= on_d;
            if total != 0.0 {
                f.scale(1.0 / self.dt)?;
                self.work.pointwise_mult(f, &self.dmask)?;
                f.axpy(-1.0, &self.work)?;
                friction = Some(&*f);
            }
        }
        // Radiation at the step's start.
        if let Some(r) = self.rad.as_mut() {
            r.power(&self.t, false)?;
        }
        let stats = match &mut self.scheme {
            Scheme::Explicit { e, g, dt_minv } => {
                e.mult_add(&self.t, g, &mut self.t_next)?;
                if let Some(r) = self.rad.as_mut() {
                    // Seed 000 eq 23 with the radiated power: − Δt M_L⁻¹ R(Tⁿ).
                    r.r1.pointwise_mult(&r.r0, dt_minv)?;
                    self.t_next.axpy(-1.0, &r.r1)?;
                }
                if let Some(q) = friction {
                    self.work.pointwise_mult(q, dt_minv)?;
                    self.t_next.axpy(1.0, &self.work)?;
                }
                if let (true, Some(r)) = (ramping, &self.ramp) {
                    self.t_next
                        .pointwise_mult(&self.t_next.duplicate_from()?, &r.free_mask)?;
                    self.t_next.axpy(1.0, &r.xd)?;
                }
                StepStats {
                    iterations: 0,
                    newton: 0,
                }
            }
            Scheme::Implicit {
                b,
                b_diag,
                g,
                rhs,
                ksp,
                seed,
                ..
            } => {
                match b_diag {
                    Some(d) => {
                        rhs.pointwise_mult(d, &self.t)?;
                        rhs.axpy(1.0, g)?;
                    }
                    None => b.mult_add(&self.t, g, rhs)?,
                }
                if let Some(q) = friction {
                    rhs.axpy(1.0, q)?;
                }
                if self.warm_start && self.extrapolate {
                    self.t_next.aypx(-1.0, &self.t)?; // 2 Tⁿ − Tⁿ⁻¹
                    self.t_next.axpy(1.0, &self.t)?;
                } else if self.warm_start {
                    self.t_next.copy_from(&self.t)?;
                }
                if std::mem::take(seed) {
                    ksp.seed_fischer_guess(&self.t)?;
                }
                let s = ksp.solve(rhs, &mut self.t_next)?;
                StepStats {
                    iterations: s.iterations,
                    newton: 0,
                }
            }
            Scheme::Newton { b, g, snes } => {
                let r = self.rad.as_mut().expect("a radiating step has its state");
                let theta = self.theta;
                let p = snes.problem_mut();
                // rhs = B Tⁿ + g − (1 − θ) R_free(Tⁿ).
                b.mult_add(&self.t, g, &mut p.rhs)?;
                p.work.pointwise_mult(&r.r0, &self.dmask)?;
                p.work.aypx(-1.0, &r.r0)?;
                p.rhs.axpy(-(1.0 - theta), &p.work)?;
                if let Some(q) = friction {
                    p.rhs.axpy(1.0, q)?;
                }
                // Converged when ‖F‖ ≤ 1e-10 ‖rhs‖, as the linear step's
                // KSP stops at 1e-10 of its right-hand side (or at 1e-10 of
                // the first residual, or a step below 1e-12).
                let atol = self.newton_rtol * p.rhs.norm2()?;
                let keep = crate::petsc::PETSC_DEFAULT;
                snes.set_tolerances(atol, keep, keep, keep as i32)?;
                self.t_next.copy_from(&self.t)?;
                let s = snes.solve(&mut self.t_next)?;
                if s.linear > REBUILD_ITERATIONS * s.newton.max(1) {
                    snes.set_lag_preconditioner(-2)?;
                }
                StepStats {
                    iterations: s.linear,
                    newton: s.newton,
                }
            }
        };
        // The handed-over heat is released.
        if let Some(f) = self.friction.as_mut() {
            f.set(0.0)?;
        }
        // The radiated heat of the step: Δt (θ R(Tⁿ⁺¹) + (1 − θ) R(Tⁿ)).
        if let Some(r) = self.rad.as_mut() {
            if self.theta != 0.0 {
                r.power(&self.t_next, true)?;
                r.sum.axpy(self.dt * self.theta, &r.r1)?;
            }
            if self.theta != 1.0 {
                r.sum.axpy(self.dt * (1.0 - self.theta), &r.r0)?;
            }
        }
        std::mem::swap(&mut self.t, &mut self.t_next);
        // An iterative step may start the next from the line through the last two.
        self.extrapolate = matches!(self.scheme, Scheme::Implicit { .. });
        self.t_sum.axpy(1.0, &self.t)?;
        self.steps += 1;
        self.steps_total += 1;
        self.iterations += stats.iterations.max(0) as u64;
        self.newton_iterations += stats.newton.max(0) as u64;
        Ok(stats)
    }

    /// Collective. Add heat (J per PETSc row, any rank's rows) to be
    /// released over the next step (frictional heating, issue 20). Every
    /// rank calls it when frictional heating is on.
    pub fn add_heat(&mut self, heat: &[(u32, f64)]) -> Result<()> {
        let Some(f) = self.friction.as_mut() else {
            return Ok(());
        };
        let rows: Vec<i32> = heat.iter().map(|&(r, _)| r as i32).collect();
        let vals: Vec<f64> = heat.iter().map(|&(_, q)| q).collect();
        f.set_values(&rows, &vals, true)?;
        f.assemble()
    }

    /// The frictional heat handed over and not yet released, per owned
    /// node of `part` (J; the copies of a node sharing a row split it),
    /// when frictional heating is on.
    pub fn pending_heat(&self, part: &Part) -> Result<Option<Vec<f64>>> {
        let Some(f) = self.friction.as_ref() else {
            return Ok(None);
        };
        let lo = part.starts[part.rank];
        let rows = f.to_local_vec()?;
        // Copies whose row is another rank's take none of it.
        let here = |p: u32| (p as usize).checked_sub(lo).filter(|&r| r < rows.len());
        let mut copies = vec![0u32; rows.len()];
        for r in part.petsc[..part.n_owned].iter().filter_map(|&p| here(p)) {
            copies[r] += 1;
        }
        Ok(Some(
            part.petsc[..part.n_owned]
                .iter()
                .map(|&p| here(p).map_or(0.0, |r| rows[r] / f64::from(copies[r])))
                .collect(),
        ))
    }

    /// The temperature of every owned node of `part` (part order).
    /// Collective when [`Part::rows_across`] (rows of other ranks gathered).
    pub fn node_temperatures(&self, part: &Part) -> Result<Vec<f64>> {
        super::node_rows::node_values(part, &self.t)
    }

    /// Collective. This rank's share of the heat flowing through contacts
    /// and across gaps now ([`super::flows`]). The gathering is kept while
    /// the rows are the same (made afresh at each history row, it cost
    /// 0.45 s of the N = 2000 heat-up on 2 ranks).
    pub fn contact_flows(
        &mut self,
        model: &Model,
        contacts: &crate::contact::ContactSet,
    ) -> Result<super::flows::Flows> {
        let rows = || super::flows::flow_rows(contacts);
        let key = crate::parallel::fingerprint(rows().map(|r| r as u64));
        let g = match &mut self.flow_gather {
            Some((k, g)) if *k == key => g,
            slot => {
                let g = crate::petsc::Gather::new(&self.t, &rows().collect::<Vec<_>>())?;
                &mut slot.insert((key, g)).1
            }
        };
        let t = g.gather(&self.t)?;
        Ok(super::flows::flows(model, contacts, &t))
    }

    /// Steps taken.
    pub fn steps_done(&self) -> u64 {
        self.steps_total
    }

    /// Collective. The heat balance since t = 0 (see the module docs).
    pub fn energy(&mut self) -> Result<EnergyAccount> {
        let n = self.steps as f64;
        let time = n * self.dt;
        let ops = &self.ops;
        // S = θ Σ_{1..N} Tⁿ + (1−θ) Σ_{0..N−1} Tⁿ = Σ_{1..N} − (1−θ)(T_N − T_0).
        let mut s = self.t_sum.duplicate()?;
        s.copy_from(&self.t_sum)?;
        s.axpy(-(1.0 - self.theta), &self.t)?;
        s.axpy(1.0 - self.theta, &self.t0)?;
        // Residual of the unconstrained equations summed over time:
        // R = M (T_N − T_0) + Δt K S − t f; its Dirichlet rows are the reactions.
        let mut dtemp = self.t.duplicate()?;
        dtemp.copy_from(&self.t)?;
        dtemp.axpy(-1.0, &self.t0)?;
        let mut r = self.t.duplicate()?;
        ops.capacity.mult(&dtemp, &mut r)?;
        ops.stiffness.mult(&s, &mut self.work)?;
        let ks_total = self.work.sum()?;
        r.axpy(self.dt, &self.work)?;
        r.axpy(-time, &ops.load)?;
        // Radiated heat: on prescribed rows the reservoir supplies it.
        let mut radiation_in = 0.0;
        if let Some(rad) = self.rad.as_ref() {
            r.axpy(1.0, &rad.sum)?;
            radiation_in = -rad.sum.sum()?;
        }
        let dirichlet_in = r.dot(&self.dmask)?;
        let stored = ops.capacity_rowsum.dot(&self.t)?;
        let stored0 = ops.capacity_rowsum.dot(&self.t0)?;
        let flux_in = time * ops.load_flux.sum()?;
        let convection_in = time * ops.load_convection.sum()? - self.dt * ks_total;
        let b = self.base;
        Ok(EnergyAccount {
            stored,
            stored_change: b.stored_change + stored - stored0,
            dirichlet_in: b.dirichlet_in + dirichlet_in,
            flux_in: b.flux_in + flux_in,
            convection_in: b.convection_in + convection_in,
            radiation_in: b.radiation_in + radiation_in,
            friction_in: b.friction_in,
        })
    }

    /// Collective. Re-assemble with a new contact set, keeping the current
    /// temperatures, step count and heat balance.
    pub fn rebuild(
        &mut self,
        petsc: &'p Petsc,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        solver: &SolverSpec,
        contacts: &ContactSet,
    ) -> crate::error::Result<()> {
        let t = self.t.to_local_vec()?;
        self.replace(
            ThermalSystem::new(petsc, comm, model, part, solver, contacts)?,
            &t,
        )
    }

    /// Continue as `next` (a new assembly) from the owned rows' temperatures
    /// `t`, with this system's heat balance, iterations and steps.
    fn replace(&mut self, mut next: ThermalSystem<'p>, t: &[f64]) -> crate::error::Result<()> {
        let account = self.energy()?;
        next.t.copy_from_slice(t)?;
        // Heat handed over and not yet released stays pending (same rows).
        if let (Some(a), Some(b)) = (self.friction.as_ref(), next.friction.as_mut()) {
            if a.local_size() == b.local_size() {
                b.copy_from(a)?;
            }
        }
        next.t0.copy_from(&next.t)?;
        next.base = account;
        next.spheres = self.spheres;
        next.iterations = self.iterations;
        next.newton_iterations = self.newton_iterations;
        next.assemblies = self.assemblies + 1;
        next.steps_total = self.steps_total;
        *self = next;
        Ok(())
    }

    /// Collective. Re-assemble on `part`'s rows numbered again (joints
    /// broke: issue 19), with a new contact set, the owned nodes keeping
    /// their temperatures `t_nodes` (part order) and the heat balance
    /// continuing: the rows a broken joint splits start at their common
    /// value, so the stored heat is unchanged.
    #[allow(clippy::too_many_arguments)]
    pub fn rebuild_rows(
        &mut self,
        petsc: &'p Petsc,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        solver: &SolverSpec,
        contacts: &ContactSet,
        t_nodes: &[f64],
    ) -> crate::error::Result<()> {
        let next = ThermalSystem::new(petsc, comm, model, part, solver, contacts)?;
        let old = self.t.to_local_vec()?;
        let rows = super::particles::rows_keeping_particles(part, t_nodes, &old);
        self.replace(next, &rows)
    }

    /// Continue from a saved state: owned temperatures (PETSc order), the
    /// heat balance so far and the steps done.
    pub fn restore(&mut self, owned: &[f64], account: EnergyAccount, steps: u64) -> Result<()> {
        self.t.copy_from_slice(owned)?;
        self.extrapolate = false;
        self.t0.copy_from(&self.t)?;
        self.t_sum.set(0.0)?;
        if let Some(r) = self.rad.as_mut() {
            r.sum.set(0.0)?;
        }
        self.steps = 0;
        self.steps_total = steps;
        let stored = account.stored;
        self.base = account;
        // energy() adds the change since t0 to the base: keep `stored` as saved.
        self.base.stored = stored;
        Ok(())
    }

    /// The heat account's running state (this rank's rows).
    pub fn account_state(&self) -> Result<AccountState> {
        Ok(AccountState {
            base: self.base,
            t0: self.t0.to_local_vec()?,
            t_sum: self.t_sum.to_local_vec()?,
            steps: self.steps,
            rad_sum: match self.rad.as_ref() {
                Some(r) => r.sum.to_local_vec()?,
                None => Vec::new(),
            },
        })
    }

    /// [`ThermalSystem::restore`], with the account's running state as
    /// saved: the account then continues bitwise as in the uninterrupted run.
    pub fn restore_exact(&mut self, owned: &[f64], state: &AccountState, steps: u64) -> Result<()> {
        self.t.copy_from_slice(owned)?;
        self.extrapolate = false;
        self.t0.copy_from_slice(&state.t0)?;
        self.t_sum.copy_from_slice(&state.t_sum)?;
        if let Some(r) = self.rad.as_mut() {
            if state.rad_sum.is_empty() {
                r.sum.set(0.0)?;
            } else {
                r.sum.copy_from_slice(&state.rad_sum)?;
            }
        }
        self.steps = state.steps;
        self.steps_total = steps;
        self.base = state.base;
        Ok(())
    }

    /// Collective. Fail if a temperature is NaN or infinite; returns the
    /// local index of the first bad owned entry on this rank, if any.
    pub fn first_non_finite(&self) -> Result<Option<usize>> {
        let norm = self.t.norm_inf()?;
        if norm.is_finite() {
            return Ok(None);
        }
        let v = self.t.view()?;
        Ok(Some(
            v.iter().position(|x| !x.is_finite()).unwrap_or(usize::MAX),
        ))
    }
}
