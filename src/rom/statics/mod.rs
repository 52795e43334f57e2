//! Static contact analysis of the reduced pair (paper Eq. 23; Eq. 18 for the baseline): gear 2
//! held at θ₂, torque T₁ on gear 1; unknowns r_b1·θ₁ and both gears' reduced coordinates.
//!
//! Every contact, whatever its law, is a scalar element: a penetration that is affine in the
//! unknowns, α = α₀ + s·(r_b1θ₁ − ref) + g₁·q₁ + g₂·q₂, a force P(α) ≥ 0, and the reduced loads
//! P·b₁, P·b₂ it puts on the gears. Equilibrium is
//!   T₁/r_b1 = Σ s·P,    K_i·q_i = Σ P·b_i   (i = 1, 2),
//! With tooth friction (`StaticModel::with_friction`, Coulomb's μ) each element also puts a
//! tangential load μσP along the flanks' transverse tangents on both gears, against the sliding
//! of a pair turning in its mesh sense: σ = sign(ω₁ρ₁ − ω₂ρ₂), the rigid flanks' sliding
//! (`dynamics::mesh_friction`), −1 before the pitch point and +1 beyond it. Its arm about gear
//! 1's axis is ρ₁ = u (the contact's place on the line of action), so the torque row becomes
//!   T₁/r_b1 = Σ P·(s + μσ·u/r_b1),
//! and the gears' loads P·(b_i − μσ·t_i), with t_i the band's rows along the tangent. Both are
//! linear in P: the condensed solver keeps its unknowns, its matrix loses its symmetry.
//! For PMOR-Hertz the elements are the axial sections of the tooth pairs, P(α) the inverse of the
//! Hertz load–approach relation and b the Hertz pressure band integrated over the flank; for the
//! penalty baseline they are flank nodes against the mating flank (node-to-surface, both passes)
//! with P = k·max(α, 0).
//!
//! Two solvers, one answer: `condensed` (the default) eliminates q and iterates on the forces of
//! the elements in contact only, the way loaded-tooth-contact codes do; `dense` is Newton on all
//! 1 + n₁ + n₂ unknowns, kept as the reference it is tested against.
//! The contact search is redone at the converged angle until the transmission error settles.

mod condensed;
mod dense;

use super::flank::Shares;
use super::reductor::ReducedGear;
use crate::closed_forms::iso6336;
use crate::closed_forms::root_stress;
use crate::contact::hertz::ApproachLaw;
use crate::contact::mesh_kinematics::{line_of_action_point_m, ContactKind, Flank, PairPlacement, SectionContact};
use crate::gear::GearPair;

/// How the flanks push on each other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactModel {
    /// Hertz line contact per axial section, approach referred to the depth h that the global
    /// attachment modes removed (`ReducedGear::local_depth_m`).
    Hertz { law: ApproachLaw },
    /// Node-to-surface penalty, both passes; each node's stiffness is `factor` × the ISO 6336
    /// mesh stiffness c_γα of its axial share of the face (the paper: two orders of magnitude
    /// stiffer than the bodies), halved per pass.
    Penalty { factor: f64 },
}

/// One contact element's state at the solution.
#[derive(Debug, Clone, Copy)]
pub struct ElementResult {
    pub pair: i64,
    pub section: usize,
    pub kind: ContactKind,
    pub force_n: f64,
    pub penetration_m: f64,
    /// Hertz contact half-width (0 for penalty elements).
    pub half_width_m: f64,
    pub radius_m: [f64; 2],
    /// The force's moment arm on gear 1 over r_b1.
    pub arm_ratio: f64,
    /// The tangential (friction) force on gear 1's flank, signed as the sliding it opposes
    /// (N; 0 without friction): μσP.
    pub friction_force_n: f64,
}

/// The outcome of one static analysis.
#[derive(Debug, Clone)]
pub struct StaticCase {
    pub theta_rad: [f64; 2],
    pub torque_nm: f64,
    /// Static transmission error r_b1θ₁ − r_b2θ₂ (m).
    pub ste_m: f64,
    /// Total normal contact force (N).
    pub mesh_force_n: f64,
    /// The normal forces' share of T₁/r_b1, Σ P·s (N): the lumped model's mesh force along the
    /// transverse line of action. T₁/r_b1 itself without friction; friction's torque is the rest.
    pub transverse_force_n: f64,
    pub pairs_in_contact: usize,
    /// Elements carrying load.
    pub elements: Vec<ElementResult>,
    /// Reduced coordinates of each gear: the global contact shape is S = ψ·q.
    pub reduced: [Vec<f64>; 2],
    pub newton_iterations: usize,
}

impl StaticCase {
    /// The load per unit face width (N/m) along the face, summed over the tooth pairs, and the
    /// axial length each value stands for. `layer_z_m` are the flank grid's node layers: a
    /// PMOR-Hertz element is a section between two layers; a penalty element (`penalty`) is a
    /// node on a layer, the end layers with half a spacing.
    pub fn face_load(&self, layer_z_m: &[f64], penalty: bool) -> (Vec<f64>, Vec<f64>) {
        let n = layer_z_m.len();
        let lengths: Vec<f64> = if penalty {
            let dz = (layer_z_m[n - 1] - layer_z_m[0]) / (n - 1) as f64;
            (0..n).map(|k| if k == 0 || k == n - 1 { 0.5 * dz } else { dz }).collect()
        } else {
            layer_z_m.windows(2).map(|w| w[1] - w[0]).collect()
        };
        let mut load = vec![0.0; lengths.len()];
        for e in &self.elements {
            load[e.section] += e.force_n;
        }
        for (w, l) in load.iter_mut().zip(&lengths) {
            *w /= l;
        }
        (load, lengths)
    }

    /// The face load factor K_Hβ: the largest load per unit face width over its mean.
    pub fn face_load_factor(&self, layer_z_m: &[f64], penalty: bool) -> f64 {
        let (load, lengths) = self.face_load(layer_z_m, penalty);
        let total: f64 = load.iter().zip(&lengths).map(|(w, l)| w * l).sum();
        let face: f64 = lengths.iter().sum();
        load.iter().fold(0.0f64, |m, &w| m.max(w)) / (total / face)
    }

    /// Friction's torque on gear 1 against its mesh sense (N·m): Σ f·u, each element's friction
    /// force (signed as the sliding) on its arm u, the contact's place on the line of action.
    /// Zero without friction; positive where it takes torque from the driver.
    pub fn friction_torque_nm(&self, pair: &GearPair) -> f64 {
        self.elements.iter().map(|e| e.friction_force_n * line_of_action_point_m(pair, e.kind, e.radius_m)).sum()
    }

    /// Normal force carried by each tooth pair, by pair index.
    pub fn force_per_pair(&self) -> Vec<(i64, f64)> {
        let mut out: Vec<(i64, f64)> = Vec::new();
        for e in &self.elements {
            match out.iter_mut().find(|(j, _)| *j == e.pair) {
                Some(entry) => entry.1 += e.force_n,
                None => out.push((e.pair, e.force_n)),
            }
        }
        out.sort_by_key(|&(j, _)| j);
        out
    }
}

/// The reduced pair with its contact model.
pub struct StaticModel<'a> {
    pub placement: PairPlacement,
    pub gears: [&'a ReducedGear; 2],
    pub contact: ContactModel,
    /// Coulomb's μ of tooth friction (0: frictionless, the default): set by `with_friction`,
    /// which checks that the basis can carry it.
    friction_coefficient: f64,
}

enum Law {
    Hertz { contact: crate::contact::hertz::LineContact, geometry: SectionContact },
    Penalty { stiffness_n_per_m: f64 },
}

/// Names an element across contact searches: (tooth pair, section or node layer, pass, node).
type ElementKey = (i64, usize, usize, usize);

struct Element {
    key: ElementKey,
    result: ElementResult,
    alpha0: f64,
    /// ∂α/∂y: the normal force's arm on gear 1 over r_b1.
    arm: f64,
    /// The element's arm in the torque balance over r_b1: `arm` plus friction's μσ·u/r_b1.
    torque_arm: f64,
    /// μσ: the tangential load per unit normal force, signed as the sliding it opposes.
    friction_per_normal: f64,
    gap: [Vec<f64>; 2],
    load: [Vec<f64>; 2],
    /// The nodal shares of `load` (unit forces along the node normals).
    load_shares: [Shares; 2],
    law: Law,
}

impl Element {
    /// P and dP/dα at penetration α.
    fn force(&self, alpha: f64) -> Result<(f64, f64), String> {
        match &self.law {
            Law::Hertz { contact, .. } => {
                let p = contact.force(alpha)?;
                Ok((p, if p > 0.0 { 1.0 / contact.compliance(p) } else { 0.0 }))
            }
            Law::Penalty { stiffness_n_per_m: k } => Ok(if alpha > 0.0 { (k * alpha, *k) } else { (0.0, 0.0) }),
        }
    }
}

impl<'a> StaticModel<'a> {
    /// `Err` when Hertz contact is asked of a basis that keeps the local deformation, or of
    /// gears reduced at different depths h.
    pub fn new(pair: &GearPair, gears: [&'a ReducedGear; 2], contact: ContactModel) -> Result<Self, String> {
        if let ContactModel::Hertz { .. } = contact {
            match (gears[0].local_depth_m, gears[1].local_depth_m) {
                (Some(a), Some(b)) if a == b => {}
                (a, b) => {
                    return Err(format!(
                        "Hertz contact needs both gears reduced without their local deformation at one depth h, \
                         got h = {a:?} / {b:?} m"
                    ))
                }
            }
        }
        Ok(StaticModel { placement: PairPlacement::new(pair), gears, contact, friction_coefficient: 0.0 })
    }

    /// The same model with tooth friction of Coulomb coefficient μ at every contact element.
    /// `Err` for μ outside [0, 1), or a standard CMS basis built without the flank tangents
    /// (`reductor::standard_cms_with_flank_tangents`), which cannot carry friction's load.
    pub fn with_friction(mut self, coefficient: f64) -> Result<Self, String> {
        if !(0.0..1.0).contains(&coefficient) {
            return Err(format!("friction coefficient must lie in [0, 1), got {coefficient}"));
        }
        if coefficient > 0.0 {
            for g in self.gears {
                g.flank_load_response(&Vec::new(), 0.0, 1.0)?;
            }
        }
        self.friction_coefficient = coefficient;
        Ok(self)
    }

    /// A copy of this model with tooth friction of coefficient μ (`with_friction`).
    pub fn frictional(&self, coefficient: f64) -> Result<StaticModel<'a>, String> {
        StaticModel {
            placement: self.placement.clone(),
            gears: self.gears,
            contact: self.contact,
            friction_coefficient: 0.0,
        }
        .with_friction(coefficient)
    }

    /// Coulomb's μ of tooth friction (0: frictionless).
    pub fn friction_coefficient(&self) -> f64 {
        self.friction_coefficient
    }

    /// σ = sign(ω₁ρ₁ − ω₂ρ₂) of a contact at u (m from T₁ on the transverse line of action) of
    /// a pair turning in its mesh sense, ω₂ = ω₁·r_b1/r_b2: −1 before the pitch point, +1
    /// beyond, 0 on it.
    fn sliding_sign(&self, point_m: f64) -> f64 {
        let p = self.pair();
        let v = point_m / p.gear1.base_radius_m - (p.loa_length_m() - point_m) / p.gear2.base_radius_m;
        if v == 0.0 {
            0.0
        } else {
            v.signum()
        }
    }

    /// (torque arm, μσ) of a contact at u with normal arm `arm` (both over r_b1).
    fn friction_arms(&self, arm: f64, point_m: f64) -> (f64, f64) {
        let mu_sigma = self.friction_coefficient * self.sliding_sign(point_m);
        (arm + mu_sigma * point_m / self.pair().gear1.base_radius_m, mu_sigma)
    }

    /// The reduced loads of gear `i` per unit normal force, shared as given: the inward normal's
    /// and friction's, b − μσ·t.
    fn load_row(&self, i: usize, shares: &Shares, friction_per_normal: f64) -> Vec<f64> {
        self.gears[i].flank_load_row(shares, 1.0, -friction_per_normal)
    }

    /// The depth h of the Hertz approach: the one the gears were reduced at.
    fn contact_depth_m(&self) -> f64 {
        self.gears[0].local_depth_m.expect("checked in StaticModel::new")
    }

    fn pair(&self) -> &GearPair {
        &self.placement.pair
    }

    fn sections(&self) -> usize {
        self.gears[0].flank.layer_z_m.len() - 1
    }

    /// The contact elements at shaft angles θ (rigid penetrations evaluated there; `te_ref` is
    /// the r_b1θ₁ − r_b2θ₂ they were evaluated at).
    fn elements(&self, theta: [f64; 2]) -> Vec<Element> {
        match self.contact {
            ContactModel::Hertz { law } => self.hertz_elements(theta, law, self.contact_depth_m()),
            ContactModel::Penalty { factor } => self.penalty_elements(theta, factor),
        }
    }

    fn hertz_elements(&self, theta: [f64; 2], law: ApproachLaw, depth_m: f64) -> Vec<Element> {
        let z = &self.gears[0].flank.layer_z_m;
        let mut out = Vec::new();
        for j in self.placement.pairs_in_reach() {
            for s in 0..self.sections() {
                let z_mid = 0.5 * (z[s] + z[s + 1]);
                let Some(c) = self.placement.section_contact(theta, j, s, z_mid) else { continue };
                let (Some(s1), Some(s2)) = (
                    self.gears[0].flank.point_shares(c.teeth[0], c.radius_m[0], s),
                    self.gears[1].flank.point_shares(c.teeth[1], c.radius_m[1], s),
                ) else {
                    continue;
                };
                let gap = [
                    self.gears[0].projected_row(&s1, self.gears[0].flank.normal(&s1)),
                    self.gears[1].projected_row(&s2, self.gears[1].flank.normal(&s2)),
                ];
                let contact = c.line_contact(self.pair(), z[s + 1] - z[s], depth_m, law);
                let point_m = line_of_action_point_m(self.pair(), c.kind, c.radius_m);
                let (torque_arm, friction_per_normal) = self.friction_arms(c.arm_ratio, point_m);
                // A point load along the gap's normal until the first force gives the band its
                // width, and its friction.
                let point_load = |i: usize, shares: &Shares| -> Vec<f64> {
                    let mut row: Vec<f64> = gap[i].iter().map(|v| -v).collect();
                    if friction_per_normal != 0.0 {
                        let friction = self.gears[i].flank_load_row(shares, 0.0, -friction_per_normal);
                        row.iter_mut().zip(&friction).for_each(|(b, f)| *b += f);
                    }
                    row
                };
                let load = [point_load(0, &s1), point_load(1, &s2)];
                out.push(Element {
                    key: (j, s, 2, 0),
                    result: ElementResult {
                        pair: j,
                        section: s,
                        kind: c.kind,
                        force_n: 0.0,
                        penetration_m: 0.0,
                        half_width_m: 0.0,
                        radius_m: c.radius_m,
                        arm_ratio: c.arm_ratio,
                        friction_force_n: 0.0,
                    },
                    alpha0: c.rigid_penetration_m,
                    arm: c.arm_ratio,
                    torque_arm,
                    friction_per_normal,
                    load,
                    gap,
                    load_shares: [s1, s2],
                    law: Law::Hertz { contact, geometry: c },
                });
            }
        }
        out
    }

    /// The Hertz pressure band of a section at force P: its nodal shares, per gear.
    fn hertz_band_shares(&self, geometry: &SectionContact, half_width_m: f64) -> Option<[Shares; 2]> {
        let p = self.pair();
        let base = [p.gear1.base_radius_m, p.gear2.base_radius_m];
        let band = |i: usize| {
            self.gears[i].flank.band_shares(
                geometry.teeth[i],
                geometry.radius_m[i],
                half_width_m,
                base[i],
                geometry.section,
            )
        };
        Some([band(0)?, band(1)?])
    }

    fn penalty_elements(&self, theta: [f64; 2], factor: f64) -> Vec<Element> {
        let p = self.pair();
        let place = &self.placement;
        let cos_bb = p.base_helix_angle_rad.cos();
        let layers = &self.gears[0].flank.layer_z_m;
        let gears = [&p.gear1, &p.gear2];
        let mut out = Vec::new();
        for j in place.pairs_in_reach() {
            let teeth = [j.rem_euclid(p.gear1.teeth as i64) as usize, j.rem_euclid(p.gear2.teeth as i64) as usize];
            // Pass `slave`: the slave gear's nodes against the master gear's flank.
            for slave in 0..2 {
                let master = 1 - slave;
                let grid = &self.gears[slave].flank;
                let Some(slot) = grid.teeth.iter().position(|&t| t == teeth[slave]) else { continue };
                let per_tooth = grid.row_radius_m.len() * layers.len();
                for k in slot * per_tooth..(slot + 1) * per_tooth {
                    let normal = grid.nodes[k].1;
                    let layer = k % layers.len();
                    let x = grid.node_xy[k];
                    let z = layers[layer];
                    let w = place.to_world(slave, theta[slave], x);
                    let own = place.to_own(master, theta[master], w);
                    let r = own[0].hypot(own[1]);
                    let g = gears[master];
                    if !(g.form_radius_m.max(g.base_radius_m)..=g.tip_radius_m).contains(&r) {
                        continue;
                    }
                    let slave_radius = x[0].hypot(x[1]);
                    let radii = if slave == 0 { [slave_radius, r] } else { [r, slave_radius] };
                    let alpha0 =
                        -cos_bb * place.distance_from_flank(master, j, z, own) - place.modification_m(radii, z);
                    if alpha0 < -0.2 * p.base_pitch_m {
                        continue;
                    }
                    let Some(master_shares) = self.gears[master].flank.layer_shares(teeth[master], r, layer) else {
                        continue;
                    };
                    let arm = if slave == 1 {
                        cos_bb
                    } else {
                        cos_bb * place.arm_on_gear1_of_gear2_normal(w, theta[1], j, z) / p.gear1.base_radius_m
                    };
                    let point_m = line_of_action_point_m(p, ContactKind::Conjugate, radii);
                    let (torque_arm, friction_per_normal) = self.friction_arms(arm, point_m);
                    let slave_shares = vec![(k, 1.0)];
                    let mut gap = [Vec::new(), Vec::new()];
                    let mut load = [Vec::new(), Vec::new()];
                    let mut load_shares = [Vec::new(), Vec::new()];
                    gap[slave] = self.gears[slave].projected_row(&slave_shares, normal);
                    load[slave] = self.load_row(slave, &slave_shares, friction_per_normal);
                    let n_master = self.gears[master].flank.normal(&master_shares);
                    gap[master] = self.gears[master].projected_row(&master_shares, n_master);
                    load[master] = self.load_row(master, &master_shares, friction_per_normal);
                    load_shares[slave] = slave_shares;
                    load_shares[master] = master_shares;
                    out.push(Element {
                        key: (j, layer, slave, k),
                        result: ElementResult {
                            pair: j,
                            section: layer,
                            kind: ContactKind::Conjugate,
                            force_n: 0.0,
                            penetration_m: 0.0,
                            half_width_m: 0.0,
                            radius_m: radii,
                            arm_ratio: arm,
                            friction_force_n: 0.0,
                        },
                        alpha0,
                        arm,
                        torque_arm,
                        friction_per_normal,
                        gap,
                        load,
                        load_shares,
                        law: Law::Penalty {
                            stiffness_n_per_m: penalty_node_stiffness_n_per_m(p, layers, layer, factor),
                        },
                    });
                }
            }
        }
        out
    }

    /// Static equilibrium at θ₂ under torque T₁ (N·m, driving), by the condensed solver.
    pub fn solve(&self, theta2: f64, torque_nm: f64) -> Result<StaticCase, String> {
        self.solve_with(theta2, torque_nm, Solver::Condensed)
    }

    /// Static equilibrium by the chosen solver. The contact search is redone at the converged
    /// angle until the transmission error settles; each search solves the equilibrium of the
    /// elements found there.
    pub fn solve_with(&self, theta2: f64, torque_nm: f64, solver: Solver) -> Result<StaticCase, String> {
        let p = self.pair();
        let (rb1, rb2) = (p.gear1.base_radius_m, p.gear2.base_radius_m);
        if !(torque_nm.is_finite() && torque_nm > 0.0) {
            return Err(format!("torque must be positive and finite, got {torque_nm} N·m"));
        }
        let at = || format!("at θ₂ = {theta2} rad, T₁ = {torque_nm} N·m");
        let target = torque_nm / rb1;
        let mut te = 0.0;
        let mut warm = WarmStart::default();
        let mut iterations = 0;
        let mut last_te = f64::NAN;
        for _search in 0..MAX_CONTACT_SEARCHES {
            let theta = [(rb2 * theta2 + te) / rb1, theta2];
            let mut elements = self.elements(theta);
            if elements.is_empty() {
                return Err(format!("no tooth pair within reach at θ₂ = {theta2} rad"));
            }
            let te_ref = te;
            let equilibrium = match solver {
                Solver::Condensed => self.condensed_equilibrium(&mut elements, te_ref, target, &mut warm),
                Solver::Dense => self.dense_equilibrium(&mut elements, te_ref, target, &mut warm),
            }
            .map_err(|m| format!("{m} {}", at()))?;
            iterations += equilibrium.iterations;
            te = te_ref + equilibrium.te_offset_m;
            if (te - last_te).abs() <= 1e-6 * te.abs() {
                // The converged contact must lie in the law's range (not the iterates).
                for e in &elements {
                    if let (Law::Hertz { contact, .. }, true) = (&e.law, e.result.force_n > 0.0) {
                        contact
                            .check_half_width(e.result.force_n)
                            .map_err(|m| format!("{}, tooth pair {}: {m}", at(), e.result.pair))?;
                    }
                }
                let loaded: Vec<ElementResult> = elements
                    .iter()
                    .map(|e| ElementResult { friction_force_n: e.friction_per_normal * e.result.force_n, ..e.result })
                    .filter(|r| r.force_n > 0.0)
                    .collect();
                let mut pairs: Vec<i64> = loaded.iter().map(|e| e.pair).collect();
                pairs.sort();
                pairs.dedup();
                // Each pair's load, at its force-weighted radius on each gear, must leave the
                // roots below yield.
                for &j in &pairs {
                    let (mut force, mut moment) = (0.0, [0.0; 2]);
                    for e in loaded.iter().filter(|e| e.pair == j) {
                        force += e.force_n;
                        moment = [moment[0] + e.force_n * e.radius_m[0], moment[1] + e.force_n * e.radius_m[1]];
                    }
                    root_stress::check_root_stress(p, force, moment.map(|m| m / force))
                        .map_err(|m| format!("{}, tooth pair {j}: {m}", at()))?;
                }
                return Ok(StaticCase {
                    theta_rad: [(rb2 * theta2 + te) / rb1, theta2],
                    torque_nm,
                    ste_m: te,
                    mesh_force_n: loaded.iter().map(|e| e.force_n).sum(),
                    transverse_force_n: loaded.iter().map(|e| e.force_n * e.arm_ratio).sum(),
                    pairs_in_contact: pairs.len(),
                    elements: loaded,
                    reduced: equilibrium.reduced,
                    newton_iterations: iterations,
                });
            }
            last_te = te;
        }
        Err(format!("the contact search did not settle in {MAX_CONTACT_SEARCHES} searches {}", at()))
    }
}

/// The penalty baseline's factor on ISO 6336-1's c_γα: the paper's "two orders of magnitude
/// stiffer than the bodies", so the penalty's own compliance adds about 1 % to the mesh's and the
/// baseline's STE sits that much above the stiff limit.
pub const DEFAULT_PENALTY_FACTOR: f64 = 100.0;

/// The penalty stiffness of one flank node in one pass (N/m): `factor` × the ISO 6336-1 mesh
/// stiffness c_γα times the node's axial share of the face (the end layers stand for half a
/// spacing), halved because both passes (each gear's nodes against the other's flank) carry the
/// load. The statics' baseline and the dynamics' reference model (`dynamics::pmor::penalty`)
/// share it, so the dynamic shapes and the dynamic contact are the same law.
pub fn penalty_node_stiffness_n_per_m(pair: &GearPair, layer_z_m: &[f64], layer: usize, factor: f64) -> f64 {
    let n = layer_z_m.len();
    let dz = (layer_z_m[n - 1] - layer_z_m[0]) / (n - 1) as f64;
    let c_gamma = iso6336::to_newton_per_metre(iso6336::mesh_stiffness_c_gamma_alpha(pair), 1.0);
    let share = if layer == 0 || layer == n - 1 { 0.5 } else { 1.0 };
    0.5 * factor * c_gamma * share * dz
}

/// The mesh's mean deflection under load (m): the loaded STE less the no-load transmission error
/// δ₀ (where the rigid flanks first touch, `PairPlacement::modification_opening_m`) at the same
/// gear-2 angles, averaged over the cases `(θ₂, STE)` of a mesh cycle. What a modification's
/// gap competes with (`PairPlacement::loaded_contact_ratio`).
pub fn mean_mesh_deflection_m(place: &PairPlacement, layer_z_m: &[f64], cases: &[(f64, f64)]) -> f64 {
    let z_mid: Vec<f64> = layer_z_m.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    let deflection: f64 = cases
        .iter()
        .map(|&(theta2, ste)| ste - place.modification_opening_m(Flank::Drive, theta2, &z_mid).unwrap_or(0.0))
        .sum();
    deflection / cases.len() as f64
}

/// Which algorithm solves the equilibrium of one contact search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solver {
    /// Condensed onto the contact forces, active set + modified Newton (`condensed.rs`): the
    /// default, and the way loaded-tooth-contact codes solve it.
    Condensed,
    /// Newton on every reduced coordinate with a dense LU (`dense.rs`): the reference the
    /// condensed solver is tested against.
    Dense,
}

/// Contact searches before the solve gives up. The contact set follows the TE (each gear's own
/// crossing of the line of action decides where conjugate contact hands over to a tip corner),
/// so a load whose TE moves the hand-overs by millimetres takes more searches than the one or
/// two of the paper's loads: 100 × Table 4's torque did not settle in 5 and does in 20.
const MAX_CONTACT_SEARCHES: usize = 20;

/// The solution of one contact search: r_b1θ₁ − te_ref, both gears' reduced coordinates and the
/// iterations it took (the elements hold their forces).
struct Equilibrium {
    te_offset_m: f64,
    reduced: [Vec<f64>; 2],
    iterations: usize,
}

/// What a contact search hands the next: the reduced coordinates and the element forces.
#[derive(Default)]
struct WarmStart {
    reduced: Option<[Vec<f64>; 2]>,
    forces: std::collections::HashMap<ElementKey, f64>,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b.iter()).map(|(x, y)| x * y).sum()
}

/// r_b1θ₁ − ref of the rigid gears (q = 0) that carries the torque: bisection on a monotone sum.
fn rigid_guess(elements: &[Element], target: f64) -> Result<f64, String> {
    let total = |te: f64| -> Result<f64, String> {
        let mut f = 0.0;
        for e in elements {
            f += e.force(e.alpha0 + e.arm * te)?.0 * e.torque_arm;
        }
        Ok(f)
    };
    let (mut lo, mut hi) = (-1e-3, 1e-6);
    while total(hi).unwrap_or(f64::INFINITY) < target {
        lo = hi;
        hi *= 2.0;
        if hi > 1e-2 {
            return Err("no rigid position carries the torque".into());
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        match total(mid) {
            Ok(f) if f < target => lo = mid,
            _ => hi = mid,
        }
        if hi - lo < 1e-15 {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}
