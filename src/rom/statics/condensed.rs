//! The static contact problem condensed onto the contact forces: a loaded-tooth-contact analysis
//! (LTCA) with the reduced gears as its influence coefficients.
//!
//! The gears' reduced coordinates are the responses to the contact forces,
//!   q_i = Σ_f P_f·u_f,i,   u = K_i⁻¹·b (`ReducedGear::load_response`),
//! and both reductions make u free: PMOR-Hertz's K_r is the identity, and the CMS baseline's
//! coordinates are the nodal forces themselves. Substituted into the penetrations,
//!   α_e = α₀_e + s_e·y + Σ_f H_ef·P_f,   H_ef = Σ_i g_e,i·u_f,i,
//! where −H is the flexibility (influence-coefficient) matrix of the contact elements. Only the
//! forces of the active elements and y = r_b1θ₁ − te_ref are unknown; on the active set A
//!   δ_e(P_e) = α_e  (e ∈ A),   Σ_A s̃_e·P_e = T₁/r_b1,
//! with s̃ = s + μσu/r_b1 the torque arm friction lengthens or shortens (and u_f the response to
//! the element's normal load and its friction together),
//! δ the law's approach (Hertz: its closed form δ(P), no inner inverse; penalty: P/k). Modified
//! Newton–Raphson (the paper's Table 2) solves it: the Jacobian diag(δ′) − H_AA bordered by s
//! leaves out how a Hertz band's width moves its loads with P.
//! The active set changes between Newton solves: an element whose Newton force turns tensile
//! leaves at once; an element outside A that penetrates the converged state joins, with a first
//! force from its own compliance. The equilibrium is the active set that neither changes.

use super::{rigid_guess, Element, Equilibrium, Law, StaticModel, WarmStart};
use crate::rom::reductor::LoadResponse;
use nalgebra::{DMatrix, DVector};

/// Newton stops when no force moves by more than this share of the largest, and y by no more
/// than this share of the transmission error.
const STEP_TOLERANCE: f64 = 1e-11;
const MAX_NEWTON: usize = 100;
const MAX_ACTIVE_SET_CHANGES: usize = 50;
/// An inactive element joins when it penetrates by more than this share of the transmission
/// error: the force it would carry below that is round-off, and an element on the edge of the
/// contact would otherwise leave and join forever.
const JOIN_TOLERANCE: f64 = 1e-10;

impl Element {
    /// The law's approach δ(P) and compliance dδ/dP at P > 0.
    fn approach(&self, force_n: f64) -> (f64, f64) {
        match &self.law {
            Law::Hertz { contact, .. } => (contact.hertz_approach(force_n), contact.compliance(force_n)),
            Law::Penalty { stiffness_n_per_m: k } => (force_n / k, 1.0 / k),
        }
    }

    /// α = α₀ + s·y + g₁·q₁ + g₂·q₂.
    fn penetration(&self, y: f64, q: &[Vec<f64>; 2]) -> f64 {
        self.alpha0 + self.arm * y + super::dot(&self.gap[0], &q[0]) + super::dot(&self.gap[1], &q[1])
    }
}

impl StaticModel<'_> {
    /// The responses of both gears to an element's unit normal force and the friction it
    /// carries (μσ along the tangent), its Hertz band sized for force P.
    fn unit_responses(&self, e: &mut Element, force_n: f64) -> Result<[LoadResponse; 2], String> {
        if let Law::Hertz { contact, geometry } = &e.law {
            let beta = contact.half_width(force_n);
            e.result.half_width_m = beta;
            if let Some(shares) = self.hertz_band_shares(geometry, beta) {
                e.load_shares = shares;
            }
        }
        let response = |i: usize| self.gears[i].flank_load_response(&e.load_shares[i], 1.0, -e.friction_per_normal);
        Ok([response(0)?, response(1)?])
    }

    /// q_i = Σ_A P_f·u_f,i.
    fn reduced_of(&self, active: &[usize], force: &[f64], responses: &[Option<[LoadResponse; 2]>]) -> [Vec<f64>; 2] {
        let mut q = [vec![0.0; self.gears[0].size()], vec![0.0; self.gears[1].size()]];
        for &f in active {
            let u = responses[f].as_ref().expect("responses of the active elements");
            for i in 0..2 {
                u[i].add_to(force[f], &mut q[i]);
            }
        }
        q
    }

    pub(super) fn condensed_equilibrium(
        &self,
        elements: &mut [Element],
        te_ref: f64,
        target: f64,
        warm: &mut WarmStart,
    ) -> Result<Equilibrium, String> {
        let m = elements.len();
        let mut force = vec![0.0; m];
        let mut y = 0.0;
        if warm.forces.is_empty() {
            // Rigid gears carrying the torque.
            y = rigid_guess(elements, target)?;
            for (e, p) in elements.iter().zip(force.iter_mut()) {
                *p = e.force(e.alpha0 + e.arm * y)?.0;
            }
        } else {
            for (e, p) in elements.iter().zip(force.iter_mut()) {
                *p = warm.forces.get(&e.key).copied().unwrap_or(0.0);
            }
        }
        let mut active: Vec<usize> = (0..m).filter(|&e| force[e] > 0.0).collect();
        let mut responses: Vec<Option<[LoadResponse; 2]>> = vec![None; m];
        let mut iterations = 0;
        for _change in 0..MAX_ACTIVE_SET_CHANGES {
            // Modified Newton on the active set.
            loop {
                iterations += 1;
                if iterations > MAX_NEWTON {
                    return Err(format!("static contact did not converge in {MAX_NEWTON} Newton iterations"));
                }
                if active.is_empty() {
                    return Err("every contact element left the contact: no position carries the torque".into());
                }
                for &f in &active {
                    responses[f] = Some(self.unit_responses(&mut elements[f], force[f])?);
                }
                let q = self.reduced_of(&active, &force, &responses);
                let na = active.len();
                let mut jacobian = DMatrix::<f64>::zeros(na + 1, na + 1);
                let mut rhs = DVector::<f64>::zeros(na + 1);
                rhs[na] = target;
                for (a, &e) in active.iter().enumerate() {
                    let el = &elements[e];
                    let (delta, compliance) = el.approach(force[e]);
                    if !(compliance > 0.0) {
                        return Err(format!(
                            "tooth pair {}: the approach law has no positive compliance at P = {:.4e} N (beyond its range)",
                            el.result.pair, force[e]
                        ));
                    }
                    rhs[a] = el.penetration(y, &q) - delta;
                    rhs[na] -= el.torque_arm * force[e];
                    for (b, &f) in active.iter().enumerate() {
                        let u = responses[f].as_ref().expect("responses of the active elements");
                        jacobian[(a, b)] = -(u[0].dot(&el.gap[0]) + u[1].dot(&el.gap[1]));
                    }
                    jacobian[(a, a)] += compliance;
                    jacobian[(a, na)] = -el.arm;
                    jacobian[(na, a)] = el.torque_arm;
                }
                let step = jacobian.lu().solve(&rhs).ok_or("singular condensed contact Jacobian")?;
                let leaving: Vec<usize> =
                    active.iter().enumerate().filter(|&(a, &e)| force[e] + step[a] <= 0.0).map(|(_, &e)| e).collect();
                if !leaving.is_empty() {
                    for e in leaving {
                        force[e] = 0.0;
                        elements[e].result.half_width_m = 0.0;
                    }
                    active.retain(|&e| force[e] > 0.0);
                    continue;
                }
                let largest = active.iter().map(|&e| force[e]).fold(0.0, f64::max);
                let mut moved = 0.0_f64;
                for (a, &e) in active.iter().enumerate() {
                    force[e] += step[a];
                    moved = moved.max(step[a].abs());
                }
                y += step[na];
                let te = (te_ref + y).abs().max(1e-9);
                if moved <= STEP_TOLERANCE * largest && step[na].abs() <= STEP_TOLERANCE * te {
                    break;
                }
            }
            // The converged state, with the bands at the converged forces.
            for &f in &active {
                responses[f] = Some(self.unit_responses(&mut elements[f], force[f])?);
            }
            let q = self.reduced_of(&active, &force, &responses);
            let threshold = JOIN_TOLERANCE * (te_ref + y).abs().max(1e-9);
            let mut joined = false;
            for e in 0..m {
                let alpha = elements[e].penetration(y, &q);
                elements[e].result.penetration_m = alpha;
                elements[e].result.force_n = force[e];
                if force[e] > 0.0 || alpha <= threshold {
                    continue;
                }
                // First force: the penetration over the law's secant compliance plus the
                // element's own structural compliance −H_ee.
                let trial = elements[e].force(alpha)?.0;
                let own = self.unit_responses(&mut elements[e], trial)?;
                let h_ee = own[0].dot(&elements[e].gap[0]) + own[1].dot(&elements[e].gap[1]);
                force[e] = alpha / (alpha / trial - h_ee.min(0.0));
                active.push(e);
                joined = true;
            }
            if !joined {
                warm.forces = active.iter().map(|&e| (elements[e].key, force[e])).collect();
                warm.reduced = Some(q.clone());
                return Ok(Equilibrium { te_offset_m: y, reduced: q, iterations });
            }
        }
        Err(format!("the active contact set did not settle in {MAX_ACTIVE_SET_CHANGES} changes"))
    }
}
