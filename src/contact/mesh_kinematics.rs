//! Where the flanks of a gear pair touch, and how far they penetrate, for given shaft angles:
//! the contact search of the static analyses (paper Table 2: "max penetration gap on each axial
//! section").
//!
//! Frames. The world's transverse plane has gear 1's axis at O₁ = (0, 0) and gear 2's at
//! O₂ = (a, 0). Each gear's FE mesh lives in its own frame, in which its mesh sense of rotation
//! is counter-clockwise (design §3: every angle is positive in its own mesh sense):
//! - gear 1: X_w = R(θ₁ + γ₁)·X₁;
//! - gear 2: X_w = O₂ + M·R(θ₂ + γ₂)·X₂ with M = diag(−1, 1, −1): gear 2 is turned over, a half
//!   turn about the world's y axis. In the transverse plane M acts as the mirror x → −x, which
//!   turns gear 2's counter-clockwise into the world's clockwise; along the axis it maps gear 2's
//!   own z to −z. Being a rotation, it keeps each gear's hand of helix: gear 1 has the spec's hand,
//!   gear 2 the opposite one, both meshed as such (`fe::gear_mesh`). In world z both transverse
//!   sections then turn the same way, s·tan β/r per metre (s = +1 when gear 1 is right-handed).
//! γ₁, γ₂ put the reference position of design §3: at θ₁ = θ₂ = 0, tooth 0 of each gear touches
//! at the operating pitch point, in the mid-plane z = 0.
//!
//! Gear 1 drives with its counter-clockwise flanks (side +1), gear 2 is driven on its clockwise
//! flanks (side −1). Tooth pair j is tooth j mod z₁ with tooth j mod z₂; along the line of action
//! (LOA) it touches at u = u_C + r_b2·θ₂ + j·p_bt + s·z·tan β_b (u from T₁, u_C the pitch point,
//! z the world's axial coordinate).
//!
//! Penetration. Two involutes of one base circle are parallel curves: measured along their common
//! normal (a tangent of the base circle) they are r_b·Δc apart, Δc the difference of their
//! involute constants c = φ ∓ inv α(r). So the distance of any point to a flank is exact and
//! cheap. For a pair inside the path of contact the flanks are conjugate and the rigid penetration
//! is cos β_b·(r_b1·θ₁ − r_b2·θ₂) — the transmission error. Outside it (a pair about to enter or
//! just leaving), a tip corner can still reach the mating flank once the teeth deflect: the
//! extended contact that shortens the single-contact zone under load. Each candidate is checked
//! and the deepest one per pair and axial section is kept.
//!
//! Coast flanks. A half turn about the line of centres (the world x axis in the mid-plane),
//! (x, y, z) → (x, −y, −z), maps each gear onto itself: every tooth is symmetric about its axis
//! and a rotation keeps the hand of helix. It takes tooth k to tooth −k, each tooth's clockwise
//! flank to its counter-clockwise one, and so the pair's coast flanks to its drive flanks. The
//! coast contact at (θ₁, θ₂) is therefore the drive contact of the half-turned pose
//! ([`PairPlacement::half_turn_angles`]), searched by the same code; the tooth thinning that the
//! profiles do not carry (`mounting.backlash_mm`) turns gear 1 back in that pose.

use super::hertz::{ApproachLaw, Body, LineContact};
use crate::gear::involute::inv;
use crate::gear::{Gear, GearPair};
use std::f64::consts::PI;

/// Which flanks of the pair touch: the drive flanks (gear 1's counter-clockwise, gear 2's
/// clockwise: transmission error ≥ 0 closes them) or the coast flanks across the backlash.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flank {
    Drive,
    Coast,
}

impl Flank {
    pub const BOTH: [Flank; 2] = [Flank::Drive, Flank::Coast];

    /// +1 on the drive flanks, −1 on the coast flanks: the sign of the normal force along the
    /// line of action (the lumped model's convention).
    pub fn sign(self) -> f64 {
        match self {
            Flank::Drive => 1.0,
            Flank::Coast => -1.0,
        }
    }

    /// The flank side (`fe::gear_mesh::FlankNode::side`) of gear `gear` (0, 1) that touches.
    pub fn side(self, gear: usize) -> i8 {
        match (self, gear) {
            (Flank::Drive, 0) | (Flank::Coast, 1) => 1,
            _ => -1,
        }
    }
}

/// Which point of which flank touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactKind {
    /// Conjugate involute contact on the line of action.
    Conjugate,
    /// Gear 2's tip corner on gear 1's flank (before the path of contact: engagement).
    TipOfGear2,
    /// Gear 1's tip corner on gear 2's flank (after the path of contact: recess).
    TipOfGear1,
}

/// One axial section of one tooth pair, at the deepest candidate point.
#[derive(Debug, Clone, Copy)]
pub struct SectionContact {
    pub pair: i64,
    /// Axial section index (the FE mesh's axial slice) and its mid-plane z (m).
    pub section: usize,
    pub z_m: f64,
    pub kind: ContactKind,
    /// Teeth (FE tooth indices) of gear 1 and gear 2.
    pub teeth: [usize; 2],
    /// Radius of the contact point on each gear's flank.
    pub radius_m: [f64; 2],
    /// Rigid-body penetration along the contact normal (m); negative: a gap.
    pub rigid_penetration_m: f64,
    /// d(rigid penetration)/d(r_b1·θ₁): how the penetration follows gear 1's rotation; also the
    /// normal force's moment arm on gear 1 over r_b1 (cos β_b on the line of action).
    pub arm_ratio: f64,
    /// Transverse radii of curvature of the two surfaces at the contact (m).
    pub curvature_radius_m: [f64; 2],
}

impl SectionContact {
    /// The Hertz line contact of this section: slice length and radii in the normal plane,
    /// approach referred to the depth `depth_m` in both bodies.
    pub fn line_contact(&self, pair: &GearPair, section_length_m: f64, depth_m: f64, law: ApproachLaw) -> LineContact {
        let cos_bb = pair.base_helix_angle_rad.cos();
        let body = |rho: f64| Body {
            youngs_modulus_pa: pair.youngs_modulus_pa,
            poisson_ratio: pair.poisson_ratio,
            radius_of_curvature_m: rho / cos_bb,
            reference_depth_m: depth_m,
        };
        LineContact {
            length_m: section_length_m / cos_bb,
            bodies: [body(self.curvature_radius_m[0]), body(self.curvature_radius_m[1])],
            law,
        }
    }
}

/// Where a contact of `kind` at radii `radius_m` (on gear 1, gear 2) touches, as a point u (m
/// from T₁) of the transverse line of action of its flank: a conjugate contact's own,
/// u = √(r₁² − r_b1²); a tip corner's is taken on the involute it touches (gear 2's flank for
/// gear 1's corner: u = T₁T₂ − √(r₂² − r_b2²)), whose tangent the sliding follows. Tooth
/// friction's arms about the axes are then u and T₁T₂ − u (`dynamics::mesh_friction`).
pub fn line_of_action_point_m(pair: &GearPair, kind: ContactKind, radius_m: [f64; 2]) -> f64 {
    let roll = |r: f64, rb: f64| (r * r - rb * rb).max(0.0).sqrt();
    match kind {
        ContactKind::TipOfGear1 => pair.loa_length_m() - roll(radius_m[1], pair.gear2.base_radius_m),
        ContactKind::Conjugate | ContactKind::TipOfGear2 => roll(radius_m[0], pair.gear1.base_radius_m),
    }
}

/// The radius of curvature of a tip corner in contact, `past_m` along the line of action beyond
/// the end of the path of contact (where conjugate contact hands over to the corner). On the
/// rounded edge it is the edge radius; at the hand-over it is the involute's at the tip. Between
/// them a C¹ blend over one edge radius of roll replaces the step that Hertz's law cannot
/// describe (its band straddles the change of curvature), and keeps the contact potential
/// W(α, R) continuous along the motion, which the energy balance of the dynamics needs.
fn corner_radius(gear: &Gear, past_m: f64) -> f64 {
    let involute = (gear.tip_radius_m.powi(2) - gear.base_radius_m.powi(2)).sqrt();
    let x = (past_m / gear.tip_edge_radius_m).clamp(0.0, 1.0);
    involute + (gear.tip_edge_radius_m - involute) * x * x * (3.0 - 2.0 * x)
}

/// The pair placed in the world, with the involute constants of its contact flanks.
#[derive(Debug, Clone)]
pub struct PairPlacement {
    pub pair: GearPair,
    gamma: [f64; 2],
    /// Involute constant of tooth 0's contact flank at z = 0 (gear 1: φ = c − inv α;
    /// gear 2: φ = c + inv α).
    flank_constant: [f64; 2],
    /// Twist of each gear's transverse section per unit of world axial length (rad/m),
    /// s·tan β / r: gear 2's own twist is −s·tan β / r₂ along its own z = −z.
    twist: [f64; 2],
    /// s = +1 if gear 1 is right-handed, −1 if left-handed.
    hand: f64,
    /// Whether the pair carries a flank modification or a misalignment (`modification_m`).
    modified: bool,
    /// The most that the modifications can close a gap (m): the reliefs and crownings only
    /// remove material, but a helix slope deviation and a misalignment add it at one face end,
    /// by at most half their amount each (`flank_can_close`).
    modification_closing_m: f64,
    /// The smallest rate at which any candidate's rigid penetration follows r_b1·θ₁
    /// (`flank_can_close`).
    smallest_arm_ratio: f64,
    /// The part of the backlash that the meshed profiles do not carry (tooth thinning,
    /// `mounting.backlash_mm`), along the line of action (m): it opens the coast gap.
    thinning_loa_m: f64,
    /// The line of action's constants, read by every section's search: cos β_b, tan β_b, the
    /// pitch point's distance from T₁ and the length T₁T₂ (m).
    cos_bb: f64,
    tan_bb: f64,
    pitch_point_m: f64,
    loa_m: f64,
}

fn rot(a: f64, p: [f64; 2]) -> [f64; 2] {
    let (s, c) = a.sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

/// Wraps an angle into (−π/z, π/z].
fn wrap(angle: f64, teeth: u32) -> f64 {
    let pitch = 2.0 * PI / teeth as f64;
    angle - pitch * (angle / pitch).round()
}

fn pressure_angle_at(gear: &Gear, r: f64) -> f64 {
    (gear.base_radius_m / r).min(1.0).acos()
}

impl PairPlacement {
    pub fn new(pair: &GearPair) -> Self {
        let alpha_t = pair.transverse_pressure_angle_rad;
        let cos_w = pair.operating_pressure_angle_rad.cos();
        let (g1, g2) = (&pair.gear1, &pair.gear2);
        let psi_w1 = g1.half_thickness_angle(g1.base_radius_m / cos_w, alpha_t);
        let psi_w2 = g2.half_thickness_angle(g2.base_radius_m / cos_w, alpha_t);
        let tan_b = pair.helix_angle_rad.tan();
        let hand = g1.helix_hand.sign();
        debug_assert_eq!(g2.helix_hand, g1.helix_hand.opposite());
        // The half turn closes the coast flanks at the profiles' own backlash: one base pitch
        // less the two tooth thicknesses at the operating pitch circles, along the LOA.
        let profile_backlash = pair.base_pitch_m - 2.0 * (g1.base_radius_m * psi_w1 + g2.base_radius_m * psi_w2);
        let mut place = PairPlacement {
            modified: pair.gear1.modification.is_some()
                || pair.gear2.modification.is_some()
                || pair.misalignment_m != 0.0,
            modification_closing_m: 0.5
                * (pair.gear1.modification.helix_slope_m.abs()
                    + pair.gear2.modification.helix_slope_m.abs()
                    + pair.misalignment_m.abs()),
            smallest_arm_ratio: 0.0,
            thinning_loa_m: pair.backlash_loa_m - profile_backlash,
            cos_bb: pair.base_helix_angle_rad.cos(),
            tan_bb: pair.base_helix_angle_rad.tan(),
            pitch_point_m: pair.pitch_point_m(),
            loa_m: pair.loa_length_m(),
            pair: pair.clone(),
            gamma: [-psi_w1, psi_w2],
            flank_constant: [
                g1.half_thickness_angle_pitch_rad + inv(alpha_t),
                -(g2.half_thickness_angle_pitch_rad + inv(alpha_t)),
            ],
            twist: [hand * tan_b / g1.pitch_radius_m, -g2.helix_hand.sign() * tan_b / g2.pitch_radius_m],
            hand,
        };
        place.smallest_arm_ratio = place.scan_smallest_arm_ratio();
        place
    }

    /// The smallest d(rigid penetration)/d(r_b1θ₁) of any candidate: cos β_b on the line of
    /// action and for gear 2's tip corner (exact), and for gear 1's tip corner the arm of gear
    /// 2's flank normal, which shrinks as the corner runs past the end of the path; scanned over
    /// the corner's whole reach (`candidate_pairs`: 0.6 base pitch and the helix's
    /// half-face shift past the end) at 200 points.
    fn scan_smallest_arm_ratio(&self) -> f64 {
        let p = &self.pair;
        let rb = [p.gear1.base_radius_m, p.gear2.base_radius_m];
        let half_b = 0.5 * p.face_width_m * p.base_helix_angle_rad.tan().abs();
        let mut smallest = p.base_helix_angle_rad.cos();
        for k in 0..=200 {
            let u = p.path_end_m + (0.6 * p.base_pitch_m + half_b) * k as f64 / 200.0;
            let theta2 = (u - p.pitch_point_m()) / rb[1];
            let theta = [rb[1] * theta2 / rb[0], theta2];
            if let Some(c) = self.section_contact(theta, 0, 0, 0.0) {
                smallest = smallest.min(c.arm_ratio);
            }
        }
        smallest
    }

    /// Whether any section of `flank` could close at these angles, given that the deformation
    /// brings no flank point more than `reach_m` nearer: false when the pose searched is backed
    /// off (TE < 0 there) so far that every candidate's rigid gap exceeds the reach. At TE = 0
    /// no candidate penetrates (the conjugate ones touch, the corners are clear: no tip
    /// interference) but where a modification adds material (at most `modification_closing_m`),
    /// and backing gear 1 off by r_b1·Δθ opens each by at least the smallest arm ratio times it.
    /// Skipping such a flank changes no result; it saves its whole search.
    pub fn flank_can_close(&self, flank: Flank, theta: [f64; 2], reach_m: f64) -> bool {
        let searched = self.searched_angles(flank, theta);
        let te = self.pair.gear1.base_radius_m * searched[0] - self.pair.gear2.base_radius_m * searched[1];
        // Wrapped to the nearest tooth: the pair index absorbs whole base pitches.
        let pb = self.pair.base_pitch_m;
        let te = te - pb * (te / pb).round();
        te >= 0.0 || self.smallest_arm_ratio * te + reach_m + self.modification_closing_m > 0.0
    }

    fn gear(&self, i: usize) -> &Gear {
        if i == 0 {
            &self.pair.gear1
        } else {
            &self.pair.gear2
        }
    }

    /// World position of a point given in gear i's own frame (transverse plane).
    pub fn to_world(&self, i: usize, theta: f64, p: [f64; 2]) -> [f64; 2] {
        let q = rot(theta + self.gamma[i], p);
        if i == 0 {
            q
        } else {
            [self.pair.center_distance_m - q[0], q[1]]
        }
    }

    /// Gear i's own-frame position of a world point.
    pub fn to_own(&self, i: usize, theta: f64, w: [f64; 2]) -> [f64; 2] {
        let q = if i == 0 { w } else { [self.pair.center_distance_m - w[0], w[1]] };
        rot(-(theta + self.gamma[i]), q)
    }

    /// Own-frame transverse point of gear i's contact flank on tooth k at radius r, world axial z.
    pub fn flank_point(&self, i: usize, tooth: i64, r: f64, z: f64) -> [f64; 2] {
        let gear = self.gear(i);
        let axis = 2.0 * PI * tooth as f64 / gear.teeth as f64 + self.twist[i] * z;
        let side = if i == 0 { 1.0 } else { -1.0 };
        let phi = axis + side * gear.half_thickness_angle(r, self.pair.transverse_pressure_angle_rad);
        [r * phi.cos(), r * phi.sin()]
    }

    /// Signed distance (m, transverse, along the flank normal; positive outside the tooth) of an
    /// own-frame point from gear i's contact flank of tooth k at axial z. Exact for involutes.
    pub fn distance_from_flank(&self, i: usize, tooth: i64, z: f64, p: [f64; 2]) -> f64 {
        let gear = self.gear(i);
        let r = p[0].hypot(p[1]);
        let axis = 2.0 * PI * tooth as f64 / gear.teeth as f64 + self.twist[i] * z;
        let phi = p[1].atan2(p[0]);
        let a = pressure_angle_at(gear, r);
        if i == 0 {
            gear.base_radius_m * wrap(phi + inv(a) - axis - self.flank_constant[0], gear.teeth)
        } else {
            -gear.base_radius_m * wrap(phi - inv(a) - axis - self.flank_constant[1], gear.teeth)
        }
    }

    /// The tooth of gear i whose contact flank at axial z is nearest to the own-frame point p
    /// (the one `distance_from_flank` measures from, whatever tooth it is given), in 0..z.
    pub fn nearest_flank_tooth(&self, i: usize, z: f64, p: [f64; 2]) -> usize {
        let gear = self.gear(i);
        let r = p[0].hypot(p[1]);
        let phi = p[1].atan2(p[0]);
        let a = pressure_angle_at(gear, r);
        let flank_angle = if i == 0 {
            phi + inv(a) - self.twist[0] * z - self.flank_constant[0]
        } else {
            phi - inv(a) - self.twist[1] * z - self.flank_constant[1]
        };
        let pitch = 2.0 * PI / gear.teeth as f64;
        ((flank_angle / pitch).round() as i64).rem_euclid(gear.teeth as i64) as usize
    }

    /// Moment arm about O₁ of the line through world point `w` along gear 2's flank normal there
    /// (for gear 1's tip corner on gear 2's flank).
    pub fn arm_on_gear1_of_gear2_normal(&self, w: [f64; 2], theta2: f64, tooth2: i64, z: f64) -> f64 {
        let own = self.to_own(1, theta2, w);
        let h = 1e-7;
        let grad = [
            (self.distance_from_flank(1, tooth2, z, [own[0] + h, own[1]])
                - self.distance_from_flank(1, tooth2, z, [own[0] - h, own[1]]))
                / (2.0 * h),
            (self.distance_from_flank(1, tooth2, z, [own[0], own[1] + h])
                - self.distance_from_flank(1, tooth2, z, [own[0], own[1] - h]))
                / (2.0 * h),
        ];
        // Gear 2's outward normal in the world (undo the rotation, then the mirror).
        let n = rot(theta2 + self.gamma[1], grad);
        let n = [-n[0], n[1]];
        // The force on gear 1 acts along +n (gear 2 pushes out of its flank); its moment about O₁
        // against gear 1's (counter-clockwise) mesh sense is −(w × n).
        -(w[0] * n[1] - w[1] * n[0])
    }

    /// The flank modifications' and the misalignment's opening (m, normal to the flanks) where
    /// gear 1's flank at radius r₁ meets gear 2's at r₂ in the section at world z (gear 2's own
    /// axial coordinate is −z): δ₁ + δ₂ + δ_ma (`gear::modification`). Zero for unmodified gears.
    pub fn modification_m(&self, radius_m: [f64; 2], z: f64) -> f64 {
        if !self.modified {
            return 0.0;
        }
        let p = &self.pair;
        let (m1, m2) = (&p.gear1.modification, &p.gear2.modification);
        let mut d = crate::gear::modification::misalignment_deviation_m(p.misalignment_m, p.face_width_m, z);
        if m1.is_some() {
            d += m1.deviation_m(p.gear1.roll_length_m(radius_m[0]), z);
        }
        if m2.is_some() {
            d += m2.deviation_m(p.gear2.roll_length_m(radius_m[1]), -z);
        }
        d
    }

    /// d(rigid penetration)/dθ of a conjugate contact through the modifications alone (per
    /// gear, in the searched pose's angles): each gear's contact point rolls along its own flank
    /// with its own angle (ρ₁ = u₁, dρ₁/dθ₁ = r_b1; ρ₂ = L − u, dρ₂/dθ₂ = −r_b2), and the
    /// penetration loses what the flank lost there, δᵢ(ρᵢ). The axial part (crowning, slope,
    /// misalignment) does not move with the angles: a section keeps its z.
    pub fn conjugate_modification_slopes(&self, radius_m: [f64; 2]) -> [f64; 2] {
        if !self.modified {
            return [0.0; 2];
        }
        let (g1, g2) = (&self.pair.gear1, &self.pair.gear2);
        let slope = |g: &Gear, r: f64| {
            if g.modification.is_some() {
                g.modification.slope_per_roll(g.roll_length_m(r))
            } else {
                0.0
            }
        };
        [-slope(g1, radius_m[0]) * g1.base_radius_m, slope(g2, radius_m[1]) * g2.base_radius_m]
    }

    /// The tooth pairs j whose contact can lie near the path at gear 2's angle θ₂ (of the pose
    /// searched): 0.6 base pitch past each end of the path, and the helix's half-face shift.
    pub fn candidate_pairs(&self, theta2: f64) -> std::ops::RangeInclusive<i64> {
        let p = &self.pair;
        let pb = p.base_pitch_m;
        let half_b = 0.5 * p.face_width_m * self.tan_bb.abs();
        let u0 = self.pitch_point_m + p.gear2.base_radius_m * theta2;
        let lo = ((p.path_start_m - 0.6 * pb - half_b - u0) / pb).ceil() as i64;
        let hi = ((p.path_end_m + 0.6 * pb + half_b - u0) / pb).floor() as i64;
        lo..=hi
    }

    /// Gear 1's angle at which `flank` first touches anywhere along the face (the sections'
    /// mid-planes `z_m`, of the pose where that flank drives) with gear 2 at θ₂ and both gears
    /// rigid: the no-load transmission error's pose. The rigid penetration grows with gear 1's
    /// turn into the flank at a rate between the smallest arm ratio and cos β_b (per r_b1·θ₁),
    /// give or take a relief's slope dδ/dρ (10⁻² and less): a step of −penetration/cos β_b
    /// overshoots by at most that share, and the iteration contracts. `None` if no candidate
    /// lies on both active profiles.
    pub fn first_touch_angle1(&self, flank: Flank, theta2: f64, z_m: &[f64]) -> Option<f64> {
        let p = &self.pair;
        let (rb1, rb2) = (p.gear1.base_radius_m, p.gear2.base_radius_m);
        let start = match flank {
            Flank::Drive => rb2 * theta2,
            Flank::Coast => rb2 * theta2 - p.backlash_loa_m,
        };
        let mut theta1 = start / rb1;
        let rate = p.base_helix_angle_rad.cos() * rb1;
        for _ in 0..200 {
            let theta = [theta1, theta2];
            let searched = self.searched_angles(flank, theta);
            let deepest = self
                .candidate_pairs(searched[1])
                .flat_map(|j| z_m.iter().enumerate().map(move |(s, &z)| (j, s, z)))
                .filter_map(|(j, s, z)| self.flank_contact(flank, theta, j, s, z))
                .map(|c| c.rigid_penetration_m)
                .fold(f64::NEG_INFINITY, f64::max);
            if !deepest.is_finite() {
                return None;
            }
            if deepest.abs() < 1e-13 {
                break;
            }
            theta1 -= flank.sign() * deepest / rate;
        }
        Some(theta1)
    }

    /// What the modifications shift the rigid first touch of `flank` by, along the line of
    /// action (m, r_b1·Δθ₁ at gear 2's θ₂): positive on the drive flanks where they open the
    /// gap, negative on the coast flanks likewise (gear 1 turns further back to touch). Zero
    /// for an unmodified pair, whose drive flanks touch at TE = 0.
    pub fn modification_opening_m(&self, flank: Flank, theta2: f64, z_m: &[f64]) -> Option<f64> {
        if !self.modified {
            return Some(0.0);
        }
        let plain = PairPlacement { modified: false, ..self.clone() };
        let rb1 = self.pair.gear1.base_radius_m;
        Some(rb1 * (self.first_touch_angle1(flank, theta2, z_m)? - plain.first_touch_angle1(flank, theta2, z_m)?))
    }

    /// The loaded contact ratio of the modified flanks, as a designer estimates it: the length
    /// of the path of contact over which the profile modifications' gap (both flanks, at
    /// mid-face, above its smallest value on the path) is at most the mesh's deflection under
    /// the load, over the base pitch. There a pair can share the load; past it the relief is
    /// deeper than the load can close. Below 1 no pair carries the load in its own right over
    /// part of each mesh cycle: the load jumps to whichever pair the deflection reaches first,
    /// and the STE spikes by the relief's excess (Harris's map beyond its minimum). For
    /// unmodified flanks it is the transverse contact ratio ε_α. `deflection_m` is the mesh's
    /// mean deflection under the load, the loaded STE less the no-load TE
    /// (`rom::statics::mean_mesh_deflection_m`).
    pub fn loaded_contact_ratio(&self, deflection_m: f64) -> f64 {
        let p = &self.pair;
        let (rb1, rb2, loa) = (p.gear1.base_radius_m, p.gear2.base_radius_m, p.loa_length_m());
        const POINTS: usize = 2000;
        let du = (p.path_end_m - p.path_start_m) / POINTS as f64;
        let gap: Vec<f64> = (0..POINTS)
            .map(|k| {
                let u = p.path_start_m + (k as f64 + 0.5) * du;
                self.modification_m([rb1.hypot(u), rb2.hypot(loa - u)], 0.0)
            })
            .collect();
        let least = gap.iter().cloned().fold(f64::INFINITY, f64::min);
        gap.iter().filter(|&&g| g - least <= deflection_m).count() as f64 * du / p.base_pitch_m
    }

    /// Whether the pair carries any flank modification or misalignment.
    pub fn is_modified(&self) -> bool {
        self.modified
    }

    /// The contact of tooth pair j in the axial section with mid-plane z, or `None` if no
    /// candidate point lies on both flanks' active profiles. θ₁, θ₂ are the shaft angles.
    pub fn section_contact(&self, theta: [f64; 2], j: i64, section: usize, z: f64) -> Option<SectionContact> {
        let p = &self.pair;
        let (g1, g2) = (&p.gear1, &p.gear2);
        let cos_bb = self.cos_bb;
        let teeth = [j.rem_euclid(g1.teeth as i64) as usize, j.rem_euclid(g2.teeth as i64) as usize];
        let u =
            self.pitch_point_m + g2.base_radius_m * theta[1] + j as f64 * p.base_pitch_m + self.hand * z * self.tan_bb;
        let loa = self.loa_m;
        let form = [g1.form_radius_m.max(g1.base_radius_m), g2.form_radius_m.max(g2.base_radius_m)];
        let mut best: Option<SectionContact> = None;
        let mut consider = |mut c: SectionContact| {
            // The flanks' modifications open the gap where they remove material; before the
            // choice, since a tip relief can hand the contact to another candidate.
            c.rigid_penetration_m -= self.modification_m(c.radius_m, z);
            if best.map_or(true, |b| c.rigid_penetration_m > b.rigid_penetration_m) {
                best = Some(c);
            }
        };
        // Gear 2's flank crosses the LOA at u; gear 1's crosses it a transverse TE further on,
        // at u₁ = u + TE (an overlap when TE > 0). Each gear's own crossing decides whether its
        // flank reaches the line and gives its radius and radius of curvature: with u for both,
        // conjugate contact outlived gear 1's tip by TE and handed over to the tip corner a
        // distance ≈ TE²/2ρ away (a jump of the contact potential the energy test saw).
        let u1 = u + g1.base_radius_m * theta[0] - g2.base_radius_m * theta[1];
        // Conjugate contact on the LOA, inside the path of contact. Two involutes of one base
        // circle are a base-circle arc apart along their common normal, so the transverse gap is
        // u − u₁ exactly (`conjugate_penetration_is_the_transmission_error` checks it against the
        // flanks placed in the world and measured, which is what this search did before issue 39).
        if u >= p.path_start_m && u1 <= p.path_end_m && u <= loa {
            consider(SectionContact {
                pair: j,
                section,
                z_m: z,
                kind: ContactKind::Conjugate,
                teeth,
                radius_m: [g1.base_radius_m.hypot(u1), g2.base_radius_m.hypot(loa - u)],
                rigid_penetration_m: cos_bb * (u1 - u),
                arm_ratio: cos_bb,
                curvature_radius_m: [u1, loa - u],
            });
        }
        // Gear 2's tip corner on gear 1's flank (the flank normal is tangent to base circle 1,
        // so the arm on gear 1 is r_b1 exactly): a candidate only before the path's start, and
        // only there placed (the corners' geometry is most of a search's transcendentals).
        if u < p.path_start_m {
            let tip2 = self.to_own(0, theta[0], self.to_world(1, theta[1], self.flank_point(1, j, g2.tip_radius_m, z)));
            let r = tip2[0].hypot(tip2[1]);
            if (form[0]..=g1.tip_radius_m).contains(&r) {
                consider(SectionContact {
                    pair: j,
                    section,
                    z_m: z,
                    kind: ContactKind::TipOfGear2,
                    teeth,
                    radius_m: [r, g2.tip_radius_m],
                    rigid_penetration_m: -cos_bb * self.distance_from_flank(0, j, z, tip2),
                    arm_ratio: cos_bb,
                    // The corner is gear 2's rounded tip edge, not its involute.
                    curvature_radius_m: [
                        (r * r - g1.base_radius_m.powi(2)).sqrt(),
                        corner_radius(g2, p.path_start_m - u),
                    ],
                });
            }
        }
        // Gear 1's tip corner on gear 2's flank: a candidate only past the path's end.
        if u1 > p.path_end_m {
            let w1 = self.to_world(0, theta[0], self.flank_point(0, j, g1.tip_radius_m, z));
            let tip1 = self.to_own(1, theta[1], w1);
            let r = tip1[0].hypot(tip1[1]);
            if (form[1]..=g2.tip_radius_m).contains(&r) {
                consider(SectionContact {
                    pair: j,
                    section,
                    z_m: z,
                    kind: ContactKind::TipOfGear1,
                    teeth,
                    radius_m: [g1.tip_radius_m, r],
                    rigid_penetration_m: -cos_bb * self.distance_from_flank(1, j, z, tip1),
                    arm_ratio: cos_bb * self.arm_on_gear1_of_gear2_normal(w1, theta[1], j, z) / g1.base_radius_m,
                    curvature_radius_m: [
                        corner_radius(g1, u1 - p.path_end_m),
                        (r * r - g2.base_radius_m.powi(2)).sqrt(),
                    ],
                });
            }
        }
        best
    }

    /// The shaft angles of the half-turned pose: its drive flanks are where this pose's coast
    /// flanks are. Gear i at θᵢ (placed at θᵢ + γᵢ) lands at −θᵢ − 2γᵢ; its tooth k is this
    /// pose's tooth −k, its axial section s this pose's section n − 1 − s (world z → −z).
    /// Gear 1 is turned back one pitch more, so that the half-turned pair j is again tooth j
    /// with tooth j (the exact image pairs gear 2's tooth j with gear 1's j − 1); its tooth k is
    /// then this pose's tooth 1 − k ([`PairPlacement::half_turn_teeth`]).
    /// The tooth thinning that the profiles do not carry turns gear 1 back by its arc on the
    /// base circle: an involute thinned along the base circle is the same involute turned, so
    /// the pose touches where the thinned teeth would, with the geometry (contact point, radii,
    /// tip corners) of touching teeth.
    pub fn half_turn_angles(&self, theta: [f64; 2]) -> [f64; 2] {
        let g1 = &self.pair.gear1;
        let pitch1 = 2.0 * PI / g1.teeth as f64;
        [
            -theta[0] - 2.0 * self.gamma[0] - pitch1 - self.thinning_loa_m / g1.base_radius_m,
            -theta[1] - 2.0 * self.gamma[1],
        ]
    }

    /// This pose's FE teeth of the half-turned pose's teeth (gear 1, gear 2): 1 − k and −k.
    pub fn half_turn_teeth(&self, teeth: [usize; 2]) -> [usize; 2] {
        let z = [self.pair.gear1.teeth as i64, self.pair.gear2.teeth as i64];
        [(1 - teeth[0] as i64).rem_euclid(z[0]) as usize, (-(teeth[1] as i64)).rem_euclid(z[1]) as usize]
    }

    /// The angles of the pose where `flank` is the drive flank: this pose for the drive flanks,
    /// the half-turned one for the coast flanks.
    pub fn searched_angles(&self, flank: Flank, theta: [f64; 2]) -> [f64; 2] {
        match flank {
            Flank::Drive => theta,
            Flank::Coast => self.half_turn_angles(theta),
        }
    }

    /// The contact of tooth pair j on the given flanks, searched in the pose where they are the
    /// drive flanks (`searched_angles`; `section` and `z` of that pose).
    pub fn flank_contact(
        &self,
        flank: Flank,
        theta: [f64; 2],
        j: i64,
        section: usize,
        z: f64,
    ) -> Option<SectionContact> {
        self.section_contact(self.searched_angles(flank, theta), j, section, z)
    }

    /// The tooth pairs j that can touch anywhere along the face for θ₂ in one angular pitch
    /// [0, 2π/z₂), extended contact included (a margin of half a base pitch at both ends).
    pub fn pairs_in_reach(&self) -> std::ops::RangeInclusive<i64> {
        let p = &self.pair;
        let (pb, half_b) = (p.base_pitch_m, 0.5 * p.face_width_m * p.base_helix_angle_rad.tan().abs());
        let u_c = p.pitch_point_m();
        let lo = ((p.path_start_m - 0.5 * pb - half_b - u_c) / pb).floor() as i64;
        let hi = ((p.path_end_m + 0.5 * pb + half_b - u_c - pb) / pb).ceil() as i64;
        lo..=hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gear::spec::HelixHand;
    use crate::gear::PairSpec;

    fn pair_with_hand(file: &str, hand: HelixHand) -> GearPair {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
        let mut spec = PairSpec::load(&path).unwrap();
        spec.rack.helix_hand = hand;
        GearPair::from_spec(&spec).unwrap()
    }

    fn pair(file: &str) -> GearPair {
        pair_with_hand(file, HelixHand::Right)
    }

    /// Closed form: conjugate involutes touch with zero gap at the reference position, and
    /// the rigid penetration equals cos β_b·(r_b1θ₁ − r_b2θ₂) everywhere on the path of contact.
    /// The contact point (gear 2's flank point placed in the world) lies on the line of action
    /// at u = u_C + r_b2·θ₂ + j·p_bt ± z·tan β_b, at radius √(r_b1² + u²) from O₁: this checks the
    /// axial term, the twist and the hand of both gears.
    #[test]
    fn conjugate_penetration_is_the_transmission_error() {
        let cases = [
            ("kurokawa_spur.toml", HelixHand::Right),
            ("kurokawa_helical.toml", HelixHand::Right),
            ("kurokawa_helical.toml", HelixHand::Left),
        ];
        for (file, hand) in cases {
            let p = pair_with_hand(file, hand);
            let place = PairPlacement::new(&p);
            let c = place.section_contact([0.0, 0.0], 0, 0, 0.0).unwrap();
            assert_eq!(c.kind, ContactKind::Conjugate);
            assert!(c.rigid_penetration_m.abs() < 1e-12, "{file}: {}", c.rigid_penetration_m);
            let (rb1, rb2) = (p.gear1.base_radius_m, p.gear2.base_radius_m);
            let cos_bb = p.base_helix_angle_rad.cos();
            for theta2 in [0.01, 0.05, 0.1] {
                let te = 3e-6;
                let theta1 = (rb2 * theta2 + te) / rb1;
                for j in -2..=2 {
                    for z in [-0.004, 0.0, 0.005] {
                        if let Some(c) = place.section_contact([theta1, theta2], j, 0, z) {
                            if c.kind == ContactKind::Conjugate {
                                assert!((c.rigid_penetration_m - cos_bb * te).abs() < 1e-10, "{file} j {j}");
                                // Gear 1's own crossing of the LOA is TE beyond gear 2's.
                                let (r1, r2) = (c.radius_m[0], c.radius_m[1]);
                                let u = (r1 * r1 - rb1 * rb1).sqrt() - te;
                                assert!((u + (r2 * r2 - rb2 * rb2).sqrt() - p.loa_length_m()).abs() < 1e-9);
                                let r1 = rb1.hypot(u);
                                let w = place.to_world(1, theta2, place.flank_point(1, j, r2, z));
                                assert!(
                                    (w[0].hypot(w[1]) - r1).abs() < 1e-9,
                                    "{file} {hand:?} j {j} z {z}: off the LOA"
                                );
                                // The gap measured: gear 2's flank point placed in the world and
                                // its distance from gear 1's flank (the search keeps the closed form).
                                let measured = -cos_bb * place.distance_from_flank(0, j, z, place.to_own(0, theta1, w));
                                assert!(
                                    (measured - c.rigid_penetration_m).abs() < 1e-12,
                                    "{file} {hand:?} j {j} z {z}: measured {measured:e} m, closed form {:e} m",
                                    c.rigid_penetration_m
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    /// Closed forms for the coast flanks (the half turn): they close when the transmission error
    /// reaches −j, j the spec's backlash along the LOA (the profiles' own, from `GearPair`'s
    /// tooth thicknesses, plus the thinning), with penetration cos β_b·(−TE − j) on the path of
    /// contact; and there the contact point, half-turned back, lies on the clockwise flank of
    /// gear 1's tooth 1 − k, thinned: at polar angle 2π(1 − k)/z₁ − ψ(r) + j_thin/r_b1
    /// (+ twist), ψ the tooth's half-thickness angle — the tooth's shape alone.
    #[test]
    fn coast_flanks_close_at_the_backlash() {
        let cases = [
            ("kurokawa_spur.toml", HelixHand::Right),
            ("kurokawa_helical.toml", HelixHand::Right),
            ("kurokawa_helical.toml", HelixHand::Left),
        ];
        for (file, hand) in cases {
            for thinning_mm in [0.0, 0.1] {
                let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
                let mut spec = PairSpec::load(&path).unwrap();
                spec.rack.helix_hand = hand;
                spec.mounting.backlash_mm = thinning_mm;
                let p = GearPair::from_spec(&spec).unwrap();
                let place = PairPlacement::new(&p);
                assert!((place.thinning_loa_m - thinning_mm * 1e-3 / p.base_helix_angle_rad.cos()).abs() < 1e-12);
                let (rb1, rb2) = (p.gear1.base_radius_m, p.gear2.base_radius_m);
                let cos_bb = p.base_helix_angle_rad.cos();
                let mut checked = 0;
                for theta2 in [0.0, 0.013, 0.03, 0.05, 0.08, 0.11] {
                    let delta = 2e-6;
                    let theta1 = (rb2 * theta2 - p.backlash_loa_m - delta) / rb1;
                    for j in -3..=3 {
                        for z in [-0.004, 0.0, 0.005] {
                            let Some(c) = place.flank_contact(Flank::Coast, [theta1, theta2], j, 0, z) else {
                                continue;
                            };
                            if c.kind != ContactKind::Conjugate {
                                continue;
                            }
                            assert!(
                                (c.rigid_penetration_m - cos_bb * delta).abs() < 1e-10,
                                "{file} {hand:?} j {j} z {z}: {:e} vs {:e}",
                                c.rigid_penetration_m,
                                cos_bb * delta
                            );
                            // At the closing angle, gear 2's contact point is on gear 1's coast
                            // flank, thinned: turned towards the tooth axis by j_thin/r_b1.
                            let theta1 = (rb2 * theta2 - p.backlash_loa_m) / rb1;
                            let turned = place.half_turn_angles([theta1, theta2]);
                            let w = place.to_world(1, turned[1], place.flank_point(1, j, c.radius_m[1], z));
                            let own = place.to_own(0, theta1, [w[0], -w[1]]);
                            let r = own[0].hypot(own[1]);
                            let tooth = place.half_turn_teeth(c.teeth)[0] as f64;
                            let flank = 2.0 * PI * tooth / p.gear1.teeth as f64 + place.twist[0] * -z
                                - p.gear1.half_thickness_angle(r, p.transverse_pressure_angle_rad)
                                + place.thinning_loa_m / rb1;
                            let off = wrap(own[1].atan2(own[0]) - flank, 1) * r;
                            assert!(off.abs() < 1e-10, "{file} {hand:?} j {j} z {z}: off the coast flank by {off:e} m");
                            checked += 1;
                        }
                    }
                }
                assert!(checked > 20, "{file}: {checked}");
            }
        }
    }

    /// `flank_can_close` never skips a flank that could touch (evidence: the search itself). Over
    /// both flanks of both example pairs, 4000 poses with the TE anywhere within ±1.5 backlash
    /// and reaches of 0–40 µm: wherever it answers "cannot close", every section of every pair
    /// in reach is open by more than the reach.
    #[test]
    fn a_flank_skipped_as_backed_off_has_every_gap_beyond_the_reach() {
        for file in ["kurokawa_spur.toml", "kurokawa_helical.toml"] {
            let p = pair(file);
            let place = PairPlacement::new(&p);
            let (rb1, rb2) = (p.gear1.base_radius_m, p.gear2.base_radius_m);
            let mut skipped = 0;
            for k in 0..4000u64 {
                // A small deterministic scramble (Weyl sequences) over θ₂, TE and the reach.
                let frac = |a: f64| (k as f64 * a).fract();
                let theta2 = frac(0.618034) * 2.0 * PI / p.gear2.teeth as f64;
                let te = (frac(0.414214) * 3.0 - 1.5) * p.backlash_loa_m;
                let reach = frac(0.732051) * 40e-6;
                let theta = [(rb2 * theta2 + te) / rb1, theta2];
                for flank in Flank::BOTH {
                    if place.flank_can_close(flank, theta, reach) {
                        continue;
                    }
                    skipped += 1;
                    for j in -4..=4 {
                        for z in [-0.5 * p.face_width_m, 0.0, 0.5 * p.face_width_m] {
                            if let Some(c) = place.flank_contact(flank, theta, j, 0, z) {
                                assert!(c.rigid_penetration_m + reach < 0.0, "{file} {flank:?} k {k}: {c:?}");
                            }
                        }
                    }
                }
            }
            assert!(skipped > 1000, "{file}: {skipped}");
        }
    }

    /// Tip-corner contacts meet the conjugate one continuously at the ends of the path of
    /// contact (A and E), and fall away (a growing gap) outside it.
    #[test]
    fn tip_corner_gap_is_continuous_at_the_ends_of_the_path_and_opens_outside() {
        let p = pair("kurokawa_spur.toml");
        let place = PairPlacement::new(&p);
        let rb2 = p.gear2.base_radius_m;
        let te = 2e-6;
        let at_u = |u: f64| {
            let theta2 = (u - p.pitch_point_m()) / rb2;
            let theta1 = (rb2 * theta2 + te) / p.gear1.base_radius_m;
            place.section_contact([theta1, theta2], 0, 0, 0.0)
        };
        for (end, outside, kind) in
            [(p.path_start_m, -1.0, ContactKind::TipOfGear2), (p.path_end_m, 1.0, ContactKind::TipOfGear1)]
        {
            let near = at_u(end + outside * 1e-7).unwrap();
            assert_eq!(near.kind, kind);
            assert!((near.rigid_penetration_m - te).abs() < 1e-8, "{kind:?}: {}", near.rigid_penetration_m);
            assert!((near.arm_ratio - 1.0).abs() < 1e-4, "{kind:?}: the arm is r_b1 at the ends of the LOA");
            let far = at_u(end + outside * 0.5e-3).unwrap();
            let farther = at_u(end + outside * 1.0e-3).unwrap();
            assert!(far.rigid_penetration_m < te - 1e-7 && farther.rigid_penetration_m < far.rigid_penetration_m);
        }
    }
}
