//! The PMOR-Hertz gear pair in floating frames (paper Sects. 3 and 5.2, design §4.5): per gear
//! the shaft angle θ and elastic coordinates η = (η_Φ, η_Ψ) on the basis [Φ, Ψ(ϑ)], Hertz contact
//! between the deformed flanks, integrated at a fixed sub-step (velocity Verlet or RK4).
//!
//! - [`model`]: the reduced pair as plain data (the model file's content);
//! - [`interpolation`]: Ψ(ϑ) between the angular samples;
//! - [`equations`]: one gear's Lagrangian terms (mass matrix, quadratic velocity vector, elastic
//!   and damping forces);
//! - [`contact`]: the contact search, Hertz law and band on the deformed flanks;
//! - [`penalty`]: node-to-surface penalty contact instead (the standard PMOR, the reference);
//! - [`contact_law`]: the one place that picks between the two by the model's contact law;
//! - [`linear`]: static equilibrium, linearization, natural frequencies, the step limit;
//! - [`integrator`]: RK4 and velocity Verlet, and the stability limit of each;
//! - [`quasi_static`]: the contact shapes and the hub direction made quasi-static (the
//!   default): what is integrated is then the slow part, the mean-axis angle and body modes;
//!   [`condensation`] holds that split and the Newton solver's state, set up once;
//! - this file: the state, the pitch anchors, the right-hand side and the RK4 step.
//!
//! The pitch anchor kᵢ of each gear is part of the state: the stored shapes cover the reference
//! pitch ϑ ∈ [−Δϑ, pitch + Δϑ), and after every step whose end leaves [0, pitch) the anchor moves
//! by one and η_Φ is re-expressed through the tooth rotation (η_Φ ← R·η_Φ); the shapes need
//! nothing, their stored samples already continue periodically.

pub mod condensation;
pub mod contact;
pub mod contact_law;
pub mod equations;
pub mod integrator;
pub mod interpolation;
pub mod linear;
pub mod model;
pub mod penalty;
pub mod quasi_static;

use crate::contact::mesh_kinematics::PairPlacement;
use crate::dynamics::mesh_friction::SlidingFriction;
use contact::{ContactLoads, GearPose, Loading};
use contact_law::contact_loads;
use equations::{gear_terms, Damping, GearTerms, Stencil};
use integrator::Integrator;
use model::PmorModel;
use nalgebra::{DMatrix, DVector};
use quasi_static::{Condensation, QuasiStatic};
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::rc::Rc;

/// The state of the reduced pair (plain data: an FMU state is a copy of it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PmorState {
    pub theta: [f64; 2],
    pub omega: [f64; 2],
    /// η = (η_Φ, η_Ψ) and η̇ per gear, in the coordinates of the anchored pitch.
    pub eta: [Vec<f64>; 2],
    pub eta_dot: [Vec<f64>; 2],
    pub anchor: [i64; 2],
    /// The torques (N·m) the quasi-static coordinates are in equilibrium with
    /// (`quasi_static`): a change books the work of the move to the new equilibrium.
    pub torques_nm: [f64; 2],
    /// ∫Σ τᵢωᵢ dt and ∫η̇ᵀDη̇ dt (J): the energy balance's external terms.
    pub input_work_j: f64,
    pub dissipated_j: f64,
    /// ∫Σ f·v dt (J): tooth friction's share of `dissipated_j`, by the trapezoid of its power over
    /// each step (never decreasing; the discrete gradient's steps only).
    #[serde(default)]
    pub friction_dissipated_j: f64,
}

/// Energies and contact at one state.
#[derive(Debug, Clone, Default)]
pub struct PmorOutputs {
    pub kinetic_j: f64,
    pub elastic_j: f64,
    pub contact_j: f64,
    pub contact: ContactLoads,
    /// The damping force Dq̇ over both gears' (θ, η), laid out as the coordinates of y.
    pub damping_force: Vec<f64>,
    /// The bore angles θ (rad): where the external torques do their work.
    pub bore_theta: [f64; 2],
}

impl PmorOutputs {
    pub fn total_energy_j(&self) -> f64 {
        self.kinetic_j + self.elastic_j + self.contact_j
    }
}

/// The reduced pair with what an instance may change.
pub struct PmorDynamics<'a> {
    pub model: &'a PmorModel,
    pub place: &'a PairPlacement,
    pub damping: [Damping; 2],
    /// Rigid inertia added at each bore (hub, shaft share), kg·m².
    pub added_inertia_kgm2: [f64; 2],
    /// The mesh damper (N·s/m): viscous on the loaded sections' approach velocity, shared by
    /// their Hertz tangent stiffness and never pulling (`contact_law::contact_loads`). The modal
    /// damping acts on each coordinate at its own frequency, far above the mesh mode's, and
    /// leaves that mode almost undamped (`fmu-build linearize`); this is what damps it.
    /// Zero by default: the paper's model has modal damping only.
    pub mesh_damping_n_s_per_m: f64,
    /// Tooth friction on the loaded sections (`contact::apply_tooth_friction`); none by default,
    /// as the paper's model.
    pub friction: Option<SlidingFriction>,
    /// How the contact force enters the elastic coordinates (the Hertz band by default).
    pub loading: Loading,
    /// The time integrator (the model's choice by default).
    pub integrator: Integrator,
    /// The Gram matrix N of the interval last used, per gear (it changes only at samples).
    gram_cache: [RefCell<Option<(usize, Rc<DMatrix<f64>>)>>; 2],
    /// The shapes' stiffness blocks of gear i's current interval (`equations::interval_shape_stiffness`).
    shape_stiffness_cache: [RefCell<Option<(usize, Rc<Vec<f64>>)>>; 2],
    /// Each gear's terms, computed in place (no allocation per right-hand side).
    terms: [RefCell<GearTerms>; 2],
    /// The quasi-static condensation (`quasi_static`), where the model asks for it.
    quasi_static: Option<QuasiStatic>,
    /// Why the condensation could not be set up (reported by the first right-hand side).
    setup_error: Option<String>,
}

impl PmorModel {
    /// Modal damping of both gears (`equations::Damping`): ζ on Φ and on the shapes, each at
    /// the coordinate's own frequency.
    pub fn damping(&self, modal_ratio: f64, shape_ratio: f64) -> [Damping; 2] {
        [Damping { modes_ratio: modal_ratio, shapes_ratio: shape_ratio }; 2]
    }

    /// The equivalent mesh mass m_e = 1/(r_b1²/J₁ + r_b2²/J₂) (kg) with the gears' inertias J.
    pub fn mesh_mass_kg(&self, inertia_kgm2: [f64; 2]) -> f64 {
        let rb = [self.gears[0].base_radius_m, self.gears[1].base_radius_m];
        1.0 / (rb[0].powi(2) / inertia_kgm2[0] + rb[1].powi(2) / inertia_kgm2[1])
    }

    /// The mesh damper's coefficient for a damping ratio ζ of the mesh mode: the lumped model's
    /// c = 2ζ√(k̄·m_e) times the build's calibration g (N·s/m; `PmorModel::mesh_damper_gain`).
    pub fn mesh_damper_n_s_per_m(&self, zeta: f64, inertia_kgm2: [f64; 2]) -> f64 {
        self.mesh_damper_gain * 2.0 * zeta * (self.mesh_stiffness_n_per_m * self.mesh_mass_kg(inertia_kgm2)).sqrt()
    }

    /// The state at rest-in-frame (η = 0) at given angles and speeds.
    pub fn initial_state(&self, theta: [f64; 2], omega: [f64; 2]) -> PmorState {
        let mut s = PmorState {
            theta,
            omega,
            eta: [0, 1].map(|i| vec![0.0; self.gears[i].elastic_size()]),
            eta_dot: [0, 1].map(|i| vec![0.0; self.gears[i].elastic_size()]),
            anchor: [0, 0],
            torques_nm: [0.0; 2],
            input_work_j: 0.0,
            dissipated_j: 0.0,
            friction_dissipated_j: 0.0,
        };
        for i in 0..2 {
            s.anchor[i] = (theta[i] / self.gears[i].pitch_rad()).floor() as i64;
        }
        s
    }
}

/// Layout of the flat state y: per gear [θ, η], then per gear [θ̇, η̇], then the two work
/// integrals. Condensed (`quasi_static`), per gear [φ, ξ] and their rates.
pub struct Layout {
    pub n_q: [usize; 2],
}

impl Layout {
    pub fn q(&self, i: usize) -> usize {
        if i == 0 {
            0
        } else {
            self.n_q[0]
        }
    }
    pub fn v(&self, i: usize) -> usize {
        self.n_q[0] + self.n_q[1] + self.q(i)
    }
    pub fn len(&self) -> usize {
        2 * (self.n_q[0] + self.n_q[1]) + 2
    }
}

impl<'a> PmorDynamics<'a> {
    pub fn new(
        model: &'a PmorModel,
        place: &'a PairPlacement,
        damping: [Damping; 2],
        added_inertia_kgm2: [f64; 2],
    ) -> Self {
        let mut d = Self::new_without_condensation(model, place, damping, added_inertia_kgm2);
        d.set_condensation(model.condensation);
        d
    }

    fn new_without_condensation(
        model: &'a PmorModel,
        place: &'a PairPlacement,
        damping: [Damping; 2],
        added_inertia_kgm2: [f64; 2],
    ) -> Self {
        PmorDynamics {
            model,
            place,
            damping,
            added_inertia_kgm2,
            mesh_damping_n_s_per_m: 0.0,
            friction: None,
            loading: Loading::HertzBand,
            integrator: model.integrator,
            gram_cache: Default::default(),
            shape_stiffness_cache: Default::default(),
            terms: [0, 1].map(|i| RefCell::new(GearTerms::new(&model.gears[i]))),
            quasi_static: None,
            setup_error: None,
        }
    }

    /// The condensed pair with the gears' splits made before for these added inertias (an FMU
    /// makes them once per inertia set: `GearSplit::new` costs an eigen-decomposition per gear).
    pub fn with_splits(
        model: &'a PmorModel,
        place: &'a PairPlacement,
        damping: [Damping; 2],
        added_inertia_kgm2: [f64; 2],
        splits: &std::sync::Arc<[quasi_static::GearSplit; 2]>,
    ) -> Self {
        let mut d = PmorDynamics::new_without_condensation(model, place, damping, added_inertia_kgm2);
        d.quasi_static = Some(QuasiStatic::from_splits(model, splits.clone()));
        d
    }

    /// Another treatment of the stiff coordinates than the model's (`quasi_static`): the same
    /// model file carries what both need, so a run can be checked against the other.
    pub fn set_condensation(&mut self, condensation: Condensation) {
        (self.quasi_static, self.setup_error) = match condensation {
            Condensation::None => (None, None),
            Condensation::QuasiStatic => match QuasiStatic::new(self.model, self.added_inertia_kgm2) {
                Ok(q) => (Some(q), None),
                Err(e) => (None, Some(e)),
            },
        };
    }

    /// The quasi-static condensation with another body-mode cut-off than the model's (Hz;
    /// `f64::INFINITY` keeps every body mode dynamic): `quasi_static::QuasiStatic::with_cutoff`.
    pub fn set_quasi_static_cutoff(&mut self, cutoff_hz: f64) {
        (self.quasi_static, self.setup_error) =
            match QuasiStatic::with_cutoff(self.model, self.added_inertia_kgm2, cutoff_hz) {
                Ok(q) => (Some(q), None),
                Err(e) => (None, Some(e)),
            };
    }

    /// The same pair (damping, inertias, loading, integrator) with another mesh damper (N·s/m):
    /// what the linearizations that vary the damper start from.
    pub fn with_mesh_damper(&self, mesh_damping_n_s_per_m: f64) -> PmorDynamics<'a> {
        // The same treatment of the stiff coordinates, its splits copied rather than made again.
        let mut d =
            PmorDynamics::new_without_condensation(self.model, self.place, self.damping, self.added_inertia_kgm2);
        d.quasi_static = self.quasi_static.as_ref().map(|q| QuasiStatic::from_splits(self.model, q.splits.clone()));
        d.setup_error = self.setup_error.clone();
        d.loading = self.loading;
        d.integrator = self.integrator;
        d.mesh_damping_n_s_per_m = mesh_damping_n_s_per_m;
        d.friction = self.friction;
        d
    }

    /// The K_ab blocks of gear i's interval starting at stored sample a0 (cached).
    pub(crate) fn shape_stiffness_block(&self, i: usize, a0: usize) -> Rc<Vec<f64>> {
        let mut cache = self.shape_stiffness_cache[i].borrow_mut();
        match &*cache {
            Some((a, block)) if *a == a0 => block.clone(),
            _ => {
                let block = Rc::new(equations::interval_shape_stiffness(&self.model.gears[i], a0));
                *cache = Some((a0, block.clone()));
                block
            }
        }
    }

    /// N of gear i's interval starting at stored sample a0 (cached).
    fn gram(&self, i: usize, a0: usize) -> Rc<DMatrix<f64>> {
        let mut cache = self.gram_cache[i].borrow_mut();
        match &*cache {
            Some((a, n)) if *a == a0 => n.clone(),
            _ => {
                let n = Rc::new(equations::interval_gram(&self.model.gears[i], a0));
                *cache = Some((a0, n.clone()));
                n
            }
        }
    }

    pub fn layout(&self) -> Layout {
        match &self.quasi_static {
            Some(q) => Layout { n_q: [1 + q.splits[0].slow_size(), 1 + q.splits[1].slow_size()] },
            None => Layout { n_q: [1 + self.model.gears[0].elastic_size(), 1 + self.model.gears[1].elastic_size()] },
        }
    }

    pub(crate) fn stencil(&self, i: usize, anchor: i64, theta: f64) -> Result<Stencil, String> {
        let g = &self.model.gears[i];
        let theta_ref = theta - anchor as f64 * g.pitch_rad();
        // A step turns a gear by half a sample interval at most (`angular_step_bound_s`); an
        // angle beyond the stored samples means the state ran away, and the user needs that, not
        // the sample bookkeeping.
        g.stencil(self.model.interpolation, theta_ref).map_err(|_| {
            format!(
                "the state ran away: gear {} stood at {} rad of its anchored pitch ({} rad), beyond the \
                 stored samples' reach of one sample interval ({} rad) past it, where a step turns the \
                 gear by half an interval at most (θ = {} rad). Either the load is beyond what this \
                 model was built for (its step is checked up to T₁ = {} N·m; rebuild with [operating] \
                 torque_nm or --rom-torques-nm at the load you run), or max_step is beyond the \
                 integrator's stability limit",
                i + 1,
                crate::gear::sig(theta_ref),
                crate::gear::sig(g.pitch_rad()),
                crate::gear::sig(g.sample_step_rad()),
                crate::gear::sig(theta),
                crate::gear::sig(self.model.linearization_torque_nm())
            )
        })
    }

    /// The state as a flat vector y (per gear [θ, η], then per gear [θ̇, η̇], then the work).
    pub fn pack(&self, s: &PmorState) -> Vec<f64> {
        let l = self.layout();
        let mut y = vec![0.0; l.len()];
        if let Some(qs) = &self.quasi_static {
            self.condensed_pack(qs, s, &mut y);
        } else {
            for i in 0..2 {
                y[l.q(i)] = s.theta[i];
                y[l.q(i) + 1..l.q(i) + l.n_q[i]].copy_from_slice(&s.eta[i]);
                y[l.v(i)] = s.omega[i];
                y[l.v(i) + 1..l.v(i) + l.n_q[i]].copy_from_slice(&s.eta_dot[i]);
            }
        }
        let n = y.len();
        y[n - 2] = s.input_work_j;
        y[n - 1] = s.dissipated_j;
        y
    }

    /// The state at y; condensed, with the fast coordinates of the last right-hand side.
    pub fn unpack(&self, y: &[f64], s: &mut PmorState) {
        let l = self.layout();
        if let Some(qs) = &self.quasi_static {
            self.condensed_unpack(qs, y, s);
        } else {
            for i in 0..2 {
                s.theta[i] = y[l.q(i)];
                s.eta[i].copy_from_slice(&y[l.q(i) + 1..l.q(i) + l.n_q[i]]);
                s.omega[i] = y[l.v(i)];
                s.eta_dot[i].copy_from_slice(&y[l.v(i) + 1..l.v(i) + l.n_q[i]]);
            }
        }
        s.input_work_j = y[y.len() - 2];
        s.dissipated_j = y[y.len() - 1];
    }

    /// ẏ at y (anchors fixed), and the outputs there.
    pub fn rhs(&self, y: &[f64], anchor: [i64; 2], torques: [f64; 2]) -> Result<(Vec<f64>, PmorOutputs), String> {
        if let Some(e) = &self.setup_error {
            return Err(e.clone());
        }
        if let Some(qs) = &self.quasi_static {
            return self.condensed_rhs(qs, y, anchor, torques);
        }
        let l = self.layout();
        let stencils = [self.stencil(0, anchor[0], y[l.q(0)])?, self.stencil(1, anchor[1], y[l.q(1)])?];
        let rates = self.mesh_damping_n_s_per_m > 0.0 || self.friction.is_some();
        let poses = [0, 1].map(|i| GearPose {
            theta: y[l.q(i)],
            anchor: anchor[i],
            stencil: stencils[i],
            eta: &y[l.q(i) + 1..l.q(i) + l.n_q[i]],
            velocity: if rates { &y[l.v(i)..l.v(i) + l.n_q[i]] } else { &[] },
        });
        let restage = |i: usize, theta: f64| self.stencil(i, anchor[i], theta);
        let contact = contact_loads(
            self.model,
            self.place,
            [&poses[0], &poses[1]],
            &restage,
            self.loading,
            self.mesh_damping_n_s_per_m,
            self.friction,
            false,
        )?;
        let mut dy = vec![0.0; y.len()];
        let mut out = PmorOutputs { damping_force: vec![0.0; l.n_q[0] + l.n_q[1]], ..Default::default() };
        let mut dissipation = contact.damper_power_w + contact.friction_power_w;
        for i in 0..2 {
            let n = l.n_q[i];
            dy[l.q(i)..l.q(i) + n].copy_from_slice(&y[l.v(i)..l.v(i) + n]);
            let mut terms = self.terms[i].borrow_mut();
            let terms = &mut *terms;
            gear_terms(
                &self.model.gears[i],
                &stencils[i],
                &self.gram(i, stencils[i].a0),
                poses[i].eta,
                y[l.v(i)],
                &y[l.v(i) + 1..l.v(i) + n],
                self.damping[i],
                terms,
            );
            out.kinetic_j += terms.kinetic_j + 0.5 * self.added_inertia_kgm2[i] * y[l.v(i)].powi(2);
            out.elastic_j += terms.elastic_j;
            out.bore_theta[i] = y[l.q(i)];
            dissipation += terms.damping_force.iter().zip(&y[l.v(i)..l.v(i) + n]).map(|(f, v)| f * v).sum::<f64>();
            let damping_force = &mut out.damping_force[l.q(i)..l.q(i) + n];
            for ((d, t), c) in damping_force.iter_mut().zip(terms.damping_force.iter()).zip(&contact.damping_force[i]) {
                *d = t + c;
            }
            // M q̈ = force + contact + torque, solved in place (the force becomes q̈).
            let rhs = terms.force.as_mut_slice();
            rhs.iter_mut().zip(&contact.force[i]).for_each(|(f, c)| *f += c);
            rhs[0] += torques[i];
            terms.mass[(0, 0)] += self.added_inertia_kgm2[i];
            solve_spd_in_place(&mut terms.mass, rhs)?;
            dy[l.v(i)..l.v(i) + n].copy_from_slice(rhs);
        }
        let n = y.len();
        dy[n - 2] = torques[0] * y[l.v(0)] + torques[1] * y[l.v(1)];
        dy[n - 1] = dissipation;
        out.contact_j = contact.potential_j;
        out.contact = contact;
        Ok((dy, out))
    }

    /// The port of gear i: the angle and speed a master reads (rad, rad/s). The bore is the
    /// floating frame and, on its own, carries about 1–2 % of the gear's inertia (the rest sits
    /// on the rim behind the web's first torsional mode): at the bore, a 40–60 kHz hub mode
    /// rings, and an explicit master that feeds a torque back from the bore's speed (a brake, a
    /// stiff shaft) destabilizes it at ordinary steps. The port is the gear's mean axis instead
    /// (Tisserand's frame, to first order in η): φ = θ + (Gx)ᵀM·u / J with J the whole rigid
    /// inertia at the bore (the FE body's and the added), u = Φη_Φ + Σₐ wₐ S_a η_Ψ, and ω = φ̇
    /// exactly. Jω is then the gear's angular momentum up to second-order terms in η, so the
    /// master's torque, applied at the bore as before, changes the port's speed through the
    /// whole inertia: the port behaves as a rigid body at every frequency a master resolves.
    /// The DTE stays bore to bore, as `fmu-build ste` measures it.
    pub fn port(&self, i: usize, s: &PmorState) -> Result<(f64, f64), String> {
        let g = &self.model.gears[i];
        if let Some(qs) = &self.quasi_static {
            return Ok(qs.splits[i].mean_axis_port(&s.eta[i], &s.eta_dot[i], s.theta[i], s.omega[i]));
        }
        let st = self.stencil(i, s.anchor[i], s.theta[i])?;
        let n_k = g.modes();
        let (eta_phi, eta_psi) = s.eta[i].split_at(n_k);
        let (etad_phi, etad_psi) = s.eta_dot[i].split_at(n_k);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let mut moment = dot(g.gx_phi.as_slice(), eta_phi);
        let mut moment_rate = dot(g.gx_phi.as_slice(), etad_phi);
        for a in 0..4 {
            let (w, dw) = (st.weights.w[a], st.weights.dw[a] / st.step);
            if w == 0.0 && dw == 0.0 {
                continue;
            }
            let gx_s = g.sample[st.a0 + a].gx_s.as_slice();
            moment += w * dot(gx_s, eta_psi);
            moment_rate += w * dot(gx_s, etad_psi) + s.omega[i] * dw * dot(gx_s, eta_psi);
        }
        let inertia = g.polar_inertia_kgm2 + self.added_inertia_kgm2[i];
        Ok((s.theta[i] + moment / inertia, s.omega[i] + moment_rate / inertia))
    }

    /// Energies and contact at a state.
    pub fn outputs(&self, s: &PmorState) -> Result<PmorOutputs, String> {
        if let Some(qs) = &self.quasi_static {
            return self.condensed_outputs(qs, s);
        }
        Ok(self.rhs(&self.pack(s), s.anchor, [0.0; 2])?.1)
    }

    /// The state a run starts from: at the given angles and speeds, the elastic coordinates at
    /// rest in their frames; condensed, the quasi-static ones at their equilibrium under `torques`.
    pub fn start_state(&self, theta: [f64; 2], omega: [f64; 2], torques: [f64; 2]) -> Result<PmorState, String> {
        let mut s = self.model.initial_state(theta, omega);
        s.torques_nm = torques;
        if let Some(qs) = &self.quasi_static {
            let y = self.pack(&s);
            self.condensed_rhs(qs, &y, s.anchor, torques)?;
            self.condensed_unpack(qs, &y, &mut s);
        }
        Ok(s)
    }

    /// One RK4 step of length h with the torques held, then the anchors re-set.
    pub fn rk4_step(&self, s: &mut PmorState, torques: [f64; 2], h: f64) -> Result<(), String> {
        let y = self.pack(s);
        let a = s.anchor;
        let stage = |y: &[f64], k: &[f64], f: f64| -> Vec<f64> { y.iter().zip(k).map(|(a, b)| a + f * b).collect() };
        let k1 = self.rhs(&y, a, torques)?.0;
        let k2 = self.rhs(&stage(&y, &k1, 0.5 * h), a, torques)?.0;
        let k3 = self.rhs(&stage(&y, &k2, 0.5 * h), a, torques)?.0;
        let k4 = self.rhs(&stage(&y, &k3, h), a, torques)?.0;
        let next: Vec<f64> =
            (0..y.len()).map(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])).collect();
        if next.iter().any(|v| !v.is_finite()) {
            return Err(format!("the PMOR-Hertz state became non-finite at step {h} s: the step is too large"));
        }
        let bore = s.theta;
        if self.quasi_static.is_some() {
            self.rhs(&next, a, torques)?; // the fast coordinates at the step's end
        }
        self.unpack(&next, s);
        if self.quasi_static.is_some() {
            // The external torques' work on the bores' travel (the flow books none).
            s.input_work_j += torques[0] * (s.theta[0] - bore[0]) + torques[1] * (s.theta[1] - bore[1]);
        }
        self.reanchor(s);
        Ok(())
    }

    /// Moves each anchor to the pitch that holds its angle, carrying η_Φ through R (forward) or
    /// Rᵀ (back). The target is computed once, so round-off at a pitch boundary (θ = −1e−20
    /// gives ϑ = pitch exactly) cannot make it oscillate; the stored samples reach past both ends.
    fn reanchor(&self, s: &mut PmorState) {
        for i in 0..2 {
            let g = &self.model.gears[i];
            let n_k = g.modes();
            let target = (s.theta[i] / g.pitch_rad()).floor() as i64;
            while s.anchor[i] != target {
                let forward = s.anchor[i] < target;
                let map: DMatrix<f64> = if forward { g.pitch_map.clone() } else { g.pitch_map.transpose() };
                for v in [&mut s.eta[i], &mut s.eta_dot[i]] {
                    let phi = DVector::from_column_slice(&v[..n_k]);
                    v[..n_k].copy_from_slice((&map * phi).as_slice());
                }
                s.anchor[i] += if forward { 1 } else { -1 };
            }
        }
    }

    /// The longest step the gears' speeds allow (s): each gear turns by at most 1/
    /// `STEPS_PER_SAMPLE_INTERVAL` of its angular sample interval Δϑ = pitch/n_θ per step.
    ///
    /// Why: the shapes are stored over ϑ ∈ [−Δϑ, pitch + Δϑ) of the anchored pitch, and the anchor
    /// moves between steps, not within one; a step whose travel exceeds Δϑ can leave the stored
    /// samples (issue 38: at a 2.9 kHz mesh frequency gear 2 of the Kurokawa pair turns 0.0118
    /// rad in 20 µs against Δϑ = 0.0101 rad). It is also the physics' rule: n_θ samples per mesh
    /// period are what the model knows of the mesh's variation, and a step that skips samples
    /// steps over the stiffness changes and contact onsets they resolve. With two steps per
    /// sample the travel of a step, its Newton iterates and a speed change within the call stay
    /// inside the stored range with a half-interval to spare.
    pub fn angular_step_bound_s(&self, s: &PmorState) -> f64 {
        (0..2)
            .map(|i| {
                let speed = s.omega[i].abs();
                let interval = self.model.gears[i].sample_step_rad();
                if speed > 0.0 {
                    interval / (STEPS_PER_SAMPLE_INTERVAL * speed)
                } else {
                    f64::INFINITY
                }
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Advances by `duration` in steps of `self.integrator` no longer than `max_step` nor than the
    /// speeds allow (`angular_step_bound_s`, taken at the call's start).
    ///
    /// A call that fails (a Newton solve that does not converge at an impact, a state the step
    /// took beyond the stored samples) is run once more from its start with a fresh solver start
    /// and an eighth of the step: what a smaller step would complete, completes. What fails
    /// then is reported with both messages.
    pub fn advance(&self, s: &mut PmorState, torques: [f64; 2], duration: f64, max_step: f64) -> Result<(), String> {
        self.advance_knowing(s, torques, duration, max_step, None).map(|_| ())
    }

    /// `advance` where the caller knows the elastic and contact energy at `s` (J; what
    /// `outputs(s)` returns as `elastic_j + contact_j`): the settling to new torques books its
    /// work against it instead of evaluating the state again. Returns the outputs at the end
    /// state where the integrator has them (the discrete gradient's last evaluation), so that a
    /// caller who needs them does not evaluate the state again; `None` otherwise.
    pub fn advance_knowing(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        duration: f64,
        max_step: f64,
        stored_j: Option<f64>,
    ) -> Result<Option<PmorOutputs>, String> {
        let max_step = max_step.min(self.angular_step_bound_s(s));
        let call_start = s.clone();
        self.advance_at(s, torques, duration, max_step, stored_j).or_else(|first| {
            *s = call_start;
            let retry_step = max_step / RETRY_STEP_DIVISOR;
            self.advance_at(s, torques, duration, retry_step, stored_j).map_err(|second| {
                format!(
                    "{second} (the call was retried from its start at a step of {retry_step:e} s after: {first}). \
                     The state is beyond what this model resolves: a load beyond the model's range, \
                     or a speed or torque change within one communication step that no sub-step follows; \
                     take shorter communication steps, or rebuild the model at the load you run"
                )
            })
        })
    }

    /// `advance` with the sub-step bound given, no retry.
    fn advance_at(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        duration: f64,
        max_step: f64,
        stored_j: Option<f64>,
    ) -> Result<Option<PmorOutputs>, String> {
        // The settling to the new torques is a time step's solve too (its tolerance, its start
        // from the last solve's tangent): a master changes the torques at every call.
        if let Some(qs) = &self.quasi_static {
            qs.stepping.set(true);
        }
        let result = self.settle_knowing(s, torques, stored_j).and_then(|first| match self.integrator {
            Integrator::Rk4 => self.rk4_advance(s, torques, duration, max_step).map(|_| None),
            Integrator::Verlet => self.verlet_advance_from(s, torques, duration, max_step, first).map(|_| None),
            // The discrete gradient needs the condensation's constant slow mass; the full pair
            // (`Condensation::None`, with its θ-dependent mass) steps with Verlet, its step rule.
            Integrator::DiscreteGradient if self.quasi_static.is_none() => {
                self.verlet_advance_from(s, torques, duration, max_step, first).map(|_| None)
            }
            Integrator::DiscreteGradient => self
                .discrete_gradient_advance_from(s, torques, duration, max_step, first)
                .map(|(_, outputs)| Some(outputs)),
        });
        if let Some(qs) = &self.quasi_static {
            qs.stepping.set(false);
        }
        result
    }

    /// Advances by `duration` in RK4 steps no longer than `max_step`.
    pub fn rk4_advance(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        duration: f64,
        max_step: f64,
    ) -> Result<(), String> {
        let (n, h) = substeps(duration, max_step);
        for _ in 0..n {
            self.rk4_step(s, torques, h)?;
        }
        Ok(())
    }
}

/// Steps per angular sample interval Δϑ at the gears' speed (`PmorDynamics::angular_step_bound_s`).
pub const STEPS_PER_SAMPLE_INTERVAL: f64 = 2.0;

/// A failed call is retried once from its start at the step over this (`PmorDynamics::advance`).
const RETRY_STEP_DIVISOR: f64 = 8.0;

/// `duration` split into the fewest equal sub-steps no longer than `max_step`: (count, length).
fn substeps(duration: f64, max_step: f64) -> (usize, f64) {
    let n = crate::dynamics::substep_count(duration, max_step);
    (n, duration / n as f64)
}

/// Solves M a = f for the symmetric positive definite mass matrix, in place: M is overwritten
/// by its Cholesky factor (lower triangle) and f by a.
fn solve_spd_in_place(m: &mut DMatrix<f64>, f: &mut [f64]) -> Result<(), String> {
    let n = f.len();
    for j in 0..n {
        let mut d = m[(j, j)];
        for k in 0..j {
            d -= m[(j, k)] * m[(j, k)];
        }
        if !(d > 0.0) {
            return Err("the reduced mass matrix is not positive definite".into());
        }
        let d = d.sqrt();
        m[(j, j)] = d;
        for i in j + 1..n {
            let mut v = m[(i, j)];
            for k in 0..j {
                v -= m[(i, k)] * m[(j, k)];
            }
            m[(i, j)] = v / d;
        }
    }
    // L z = f, then Lᵀ a = z.
    for i in 0..n {
        let mut v = f[i];
        for k in 0..i {
            v -= m[(i, k)] * f[k];
        }
        f[i] = v / m[(i, i)];
    }
    for i in (0..n).rev() {
        let mut v = f[i];
        for k in i + 1..n {
            v -= m[(k, i)] * f[k];
        }
        f[i] = v / m[(i, i)];
    }
    Ok(())
}
