//! The root fillet: the trochoidal envelope that the rounded tip of the rack cutter generates.
//!
//! Frame: gear center O at the origin, the rack below it. The rack's datum line lies at distance
//! r + x·m from O; the gear's pitch circle (radius r) rolls without slip on the rack line at
//! distance r. When the gear turns by φ (counter-clockwise) the rack slides by r·φ, and the
//! instantaneous center of the relative motion is the pitch point I = (0, −r). The cutter point
//! that generates the gear surface is where the normal to the cutter passes through I (the
//! law of gearing): on the tip-rounding circle of center C, that is P = C + ρ·(C − I)/|C − I|.

/// The rack cutter in the transverse section (SI). Heights are the normal rack's (h_fP = h*·m_n);
/// the pitch along the pitch line is π·m_t and the flank angle α_t. The tip rounding, a circle of
/// radius ρ in the normal section, is an ellipse in the transverse one; it is taken here as the
/// circle ρ_t that ends the straight flank at the same height as the normal rack does,
/// ρ_t = ρ(1 − sin α_n)/(1 − sin α_t), so that the form circle is the same in both views (exact for
/// spur gears).
pub struct RackCutter {
    pub pitch_m: f64,
    pub pressure_angle_rad: f64,
    pub dedendum_m: f64,
    pub tip_radius_m: f64,
    pub profile_shift_m: f64,
}

/// Points (radius, half tooth-thickness angle) of the fillet, from the root circle up to the
/// point where it meets the involute, sorted by radius.
pub fn fillet_profile(cutter: &RackCutter, pitch_radius_m: f64, teeth: u32) -> Vec<(f64, f64)> {
    let r = pitch_radius_m;
    let rho = cutter.tip_radius_m;
    let alpha = cutter.pressure_angle_rad;
    // Rounding center, in rack coordinates: height above the datum (towards O) and horizontal
    // offset from the rack tooth's centerline (the rack tooth is centered on the gear space).
    let h_c = cutter.dedendum_m - rho;
    let x_c = cutter.pitch_m / 4.0 - h_c * alpha.tan() - rho / alpha.cos();
    let y_c = -(r + cutter.profile_shift_m) + h_c;
    // The tooth to the right of the space centered at −π/2 has its centerline at −π/2 + π/z.
    let tooth_axis = -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / teeth as f64;
    let mut points: Vec<(f64, f64)> = Vec::new();
    // From φ = 0 (the rounding circle at the bottom of the space: the root circle) the generated
    // point climbs the right tooth's fillet while the half-thickness angle shrinks; at its minimum
    // the fillet meets the involute tangentially and the straight cutter flank takes over.
    let n = 4000;
    for i in 0..=n {
        let phi = 0.6 * i as f64 / n as f64;
        let c = (x_c + r * phi, y_c);
        let (dx, dy) = (c.0 - 0.0, c.1 + r);
        let len = dx.hypot(dy);
        if len < 1e-15 {
            continue;
        }
        let p = (c.0 + rho * dx / len, c.1 + rho * dy / len);
        // Into the gear frame: undo the gear's rotation by φ.
        let (s, co) = (-phi).sin_cos();
        let pg = (co * p.0 - s * p.1, s * p.0 + co * p.1);
        let radius = pg.0.hypot(pg.1);
        let half_angle = tooth_axis - pg.1.atan2(pg.0);
        if let Some(&(_, previous)) = points.last() {
            if half_angle >= previous {
                break;
            }
        }
        points.push((radius, half_angle));
    }
    points
}
