//! An environment's light as nine spherical-harmonic coefficients (Ramamoorthi and
//! Hanrahan 2001), turned into the quadratic polynomials in a view-space direction that the
//! shaders evaluate (`frame.environment_quadratics`, irradiance.wgsl): the irradiance E(n)
//! and the pre-filtered radiance SSDO weighs its unoccluded directions with. vrao's
//! renderer builds them from its environment map; the AO engine from a host's
//! coefficients ([`crate::HostLight`]).

use glam::{Mat3, Vec3};
use std::f32::consts::{PI, TAU};

/// Nine SH coefficients as the quadratic polynomial in the unit direction ω = (x, y, z)
/// that they are: f(ω) = a + b·ω + qxx x² + qyy y² + qzz z² + qxy xy + qxz xz + qyz yz,
/// returned as [a, bx, by, bz, qxx, qyy, qzz, qxy, qxz, qyz] (rgb each). The basis order
/// is 1, y, z, x, xy, yz, 3z² − 1, xz, x² − y² (`sh9_basis` of vrao-render).
pub fn sh9_quadratic(c: &[Vec3; 9]) -> [Vec3; 10] {
    [
        c[0] * 0.282_095 - c[6] * 0.315_392,
        c[3] * 0.488_603,
        c[1] * 0.488_603,
        c[2] * 0.488_603,
        c[8] * 0.546_274,
        c[8] * -0.546_274,
        c[6] * (3.0 * 0.315_392),
        c[4] * 1.092_548,
        c[7] * 1.092_548,
        c[5] * 1.092_548,
    ]
}

/// A quadratic of [`sh9_quadratic`]'s form in the world direction, re-expressed in the
/// direction v of a view whose world direction is `world_from_view` · v:
/// f(R v) = a + (Rᵀb)·v + vᵀ(RᵀQR)v. Done once per eye, so the shaders evaluate
/// environment light in view space without turning each pixel's vectors into the world.
pub fn quadratic_in_view(q: &[Vec3; 10], world_from_view: Mat3) -> [Vec3; 10] {
    let mut out = [Vec3::ZERO; 10];
    out[0] = q[0];
    for channel in 0..3 {
        let c = |k: usize| q[k][channel];
        let linear = world_from_view.transpose() * Vec3::new(c(1), c(2), c(3));
        // The symmetric matrix of the quadratic part: a cross term's coefficient is
        // shared by its two off-diagonal entries.
        let symmetric = Mat3::from_cols(
            Vec3::new(c(4), 0.5 * c(7), 0.5 * c(8)),
            Vec3::new(0.5 * c(7), c(5), 0.5 * c(9)),
            Vec3::new(0.5 * c(8), 0.5 * c(9), c(6)),
        );
        let turned = world_from_view.transpose() * symmetric * world_from_view;
        let coefficients = [
            linear.x,
            linear.y,
            linear.z,
            turned.x_axis.x,
            turned.y_axis.y,
            turned.z_axis.z,
            2.0 * turned.y_axis.x,
            2.0 * turned.z_axis.x,
            2.0 * turned.z_axis.y,
        ];
        for (k, value) in coefficients.into_iter().enumerate() {
            out[k + 1][channel] = value;
        }
    }
    out
}

/// The radiance low-passed to its first two bands from the irradiance's coefficients
/// (band weights 1, 0.75, 0 over the clamped-cosine kernel π, 2π/3, π/4: band 1 as a
/// three-band Hann window has it, band 2 dropped), the pre-filtered environment SSDO reads
/// per direction (Ritschel et al. 2009 ask for a pre-smoothed map). Linear in the
/// direction, so a sum over weighted directions needs only their first moments.
pub fn prefiltered_radiance(irradiance: &[Vec3; 9]) -> [Vec3; 9] {
    const WINDOW_OVER_KERNEL: [f32; 9] =
        [1.0 / PI, 0.75 * 3.0 / TAU, 0.75 * 3.0 / TAU, 0.75 * 3.0 / TAU, 0.0, 0.0, 0.0, 0.0, 0.0];
    std::array::from_fn(|k| irradiance[k] * WINDOW_OVER_KERNEL[k])
}

/// `frame.environment_quadratics` for up to two views from the irradiance's nine SH
/// coefficients in world space and each view's world-from-view rotation: the irradiance
/// of view 0 and 1, then the pre-filtered radiance of view 0 and 1.
pub(crate) fn view_quadratics(irradiance: &[Vec3; 9], world_from_views: &[Mat3]) -> [[[f32; 4]; 10]; 4] {
    let mut out = [[[0.0; 4]; 10]; 4];
    let (e, l) = (sh9_quadratic(irradiance), sh9_quadratic(&prefiltered_radiance(irradiance)));
    for (index, rotation) in world_from_views.iter().enumerate().take(2) {
        let in_view = |q: &[Vec3; 10]| quadratic_in_view(q, *rotation).map(|c| c.extend(0.0).to_array());
        out[index] = in_view(&e);
        out[2 + index] = in_view(&l);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_irradiance_is_the_same_in_every_view_and_its_radiance_is_a_pi_th() {
        // E = π L for a constant radiance L: c0 = π L / Y0 with Y0 = 0.282095.
        let l = Vec3::new(1.0, 0.5, 0.25);
        let mut c = [Vec3::ZERO; 9];
        c[0] = l * PI / 0.282_095;
        let turned = Mat3::from_quat(glam::Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.2));
        let q = view_quadratics(&c, &[Mat3::IDENTITY, turned]);
        for view in 0..2 {
            for ch in 0..3 {
                assert!((q[view][0][ch] - PI * l[ch]).abs() < 1e-4, "{q:?}");
                assert!((q[2 + view][0][ch] - l[ch]).abs() < 1e-4, "{q:?}");
                assert!((1..10).all(|k| q[view][k][ch].abs() < 1e-6 && q[2 + view][k][ch].abs() < 1e-6));
            }
        }
    }
}
