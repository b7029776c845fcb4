//! Directional albedo tables of GGX microfacet lobes, for multiple-scattering energy
//! compensation:
//!
//! - Kulla & Conty 2017, "Revisiting Physically Based Shading at Imageworks" (SIGGRAPH
//!   course): the albedo E(μ, α) of single-scattering GGX reflection with F = 1 and its
//!   cosine-weighted average E_avg(α) = 2∫E(μ)μ dμ build the multiple-scattering lobe of
//!   [`super::microfacet::MicrofacetReflection`] (metals, dielectric specular);
//! - Turquin 2019, "Practical multiple scattering compensation for microfacet models"
//!   (Weta Digital tech report): rough glass scales its single-scattering BSDF by
//!   1/E(μo) with E the albedo of reflection plus transmission (radiance compression
//!   left out), one table entering (η > 1) and one exiting (η < 1).
//!
//! The dielectric-reflection table (Fresnel-exact, single scattering) gives the
//! albedo of the specular layer over an opaque base, so that the base can be attenuated
//! by what the layer reflects.
//!
//! Anisotropic GGX reads the F = 1 table at the geometric-mean alpha √(αx·αy), as
//! OpenPBR's MaterialX reference (`mx_average_alpha`) and Cycles
//! (`microfacet_ggx_albedo_scaling`) do, so anisotropic metal renders as they render
//! it: that compensates less than the lobe loses where the view sees the rough axis (a
//! white furnace keeps 0.90–0.96 at anisotropy 0.8, as Cycles' does;
//! benches/materials/RESULTS.md). The dielectric tables read anisotropic lobes at
//! [`directional_alpha`] (dielectric specular, η ≥ 1: within 2 % in the furnace tests)
//! or at [`min_alpha`] (glass, and reflection under total internal reflection, where no
//! single alpha fits: they compensate less, never too much).
//!
//! Axes: μ = cos θo linear in [0, 1]; √α linear in [0, 1] (α beyond 1 reads the edge);
//! η through √((η − 1)/(η + 1)) / √(1/2) linear in [0, 1] for η in [1, 3] (the
//! exiting tables take 1/η). Lookup is bi/trilinear, allocation-free. The tables in
//! `albedo_tables.rs` are written by the ignored test
//! `material::tests::generate_albedo_tables` (see [`generator`]); the test
//! `material::tests::albedo_tables_match_fresh_integration` recomputes entries.

use super::albedo_tables as t;
use super::microfacet::Ggx;
use glam::Vec3A;

/// Points along μ and √α of the F = 1 table.
pub const N_2D: usize = 32;
/// Points along μ, √α and η of the dielectric tables.
pub const N_3D: usize = 16;
/// Largest index of refraction the dielectric tables reach (beyond reads the edge).
pub const ETA_MAX: f32 = 3.0;

/// (lower index, fraction) of `x` in [0, 1] on `n` evenly spaced nodes; NaN reads 0.
#[inline]
fn coord(x: f32, n: usize) -> (usize, f32) {
    let x = if x >= 0.0 { x.min(1.0) } else { 0.0 };
    let s = x * (n - 1) as f32;
    // Through i32: s is in [0, n − 1] here, and a float's saturating cast to usize is
    // ~3× the instructions of one to i32 (a sixth of a table lookup's).
    let i = (s as i32 as usize).min(n - 2);
    (i, s - i as f32)
}

#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

fn alpha_coord(alpha: f32) -> f32 {
    if alpha > 0.0 {
        alpha.sqrt()
    } else {
        0.0
    }
}

/// The η axis coordinate of a relative index and whether it is the exiting table.
fn eta_coord(eta: f32) -> (f32, bool) {
    let (e, exit) = if eta >= 1.0 {
        (eta, false)
    } else if eta > 0.0 {
        (1.0 / eta, true)
    } else {
        (1.0, false)
    };
    (eta_to_axis(e), exit)
}

/// η ≥ 1 to the η axis in [0, 1].
pub fn eta_to_axis(eta: f32) -> f32 {
    let e = eta.clamp(1.0, ETA_MAX);
    let max = ((ETA_MAX - 1.0) / (ETA_MAX + 1.0)).sqrt();
    ((e - 1.0) / (e + 1.0)).sqrt() / max
}

/// The inverse of [`eta_to_axis`].
pub fn axis_to_eta(x: f32) -> f32 {
    let max = ((ETA_MAX - 1.0) / (ETA_MAX + 1.0)).sqrt();
    let r = (x * max).powi(2);
    (1.0 + r) / (1.0 - r)
}

fn bilinear(table: &[f32], n: usize, y: f32, x: f32) -> f32 {
    let (j, ty) = coord(y, n);
    let (i, tx) = coord(x, n);
    cell(table, n, j * n + i, ty, tx)
}

/// The bilinear blend of the four nodes from `at` (the lower corner's index in a table
/// `n` wide): one bounds check for the four loads.
#[inline(always)]
fn cell(table: &[f32], n: usize, at: usize, ty: f32, tx: f32) -> f32 {
    let c = &table[at..at + n + 2];
    lerp(lerp(c[0], c[1], tx), lerp(c[n], c[n + 1], tx), ty)
}

/// The coordinates along y and x are found once for both slices.
fn trilinear(table: &[f32], n: usize, z: f32, y: f32, x: f32) -> f32 {
    let (k, tz) = coord(z, n);
    let (j, ty) = coord(y, n);
    let (i, tx) = coord(x, n);
    let at = k * n * n + j * n + i;
    let a = cell(table, n, at, ty, tx);
    let b = cell(table, n, at + n * n, ty, tx);
    lerp(a, b, tz)
}

fn linear(table: &[f32], n: usize, x: f32) -> f32 {
    let (i, t) = coord(x, n);
    lerp(table[i], table[i + 1], t)
}

/// The isotropic alpha at which anisotropic GGX reads the F = 1 tables: the geometric
/// mean √(αx·αy) (module doc).
pub fn mean_alpha(g: &Ggx) -> f32 {
    if g.alpha_x == g.alpha_y {
        g.alpha_x
    } else {
        (g.alpha_x * g.alpha_y).sqrt()
    }
}

/// Albedo of single-scattering GGX reflection with F = 1 towards `w` (the local frame
/// of `g`), anisotropic lobes at [`mean_alpha`].
pub fn ggx_e_dir(g: &Ggx, w: Vec3A) -> f32 {
    ggx_e(w.z.abs(), mean_alpha(g))
}

/// The cosine-weighted average of [`ggx_e_dir`] over the hemisphere.
pub fn ggx_e_avg_of(g: &Ggx) -> f32 {
    ggx_e_avg(mean_alpha(g))
}

/// The isotropic alpha at which an anisotropic `g` reads the (isotropic) dielectric
/// tables towards `w`: the roughness of the slopes in `w`'s plane of incidence (what
/// decides Fresnel and total internal reflection), α² = αx²wx² + αy²wy² + μ²α_rms², which
/// turns into the mean α_rms² towards the normal, where no plane is preferred.
/// `g`'s own alpha when isotropic.
pub fn directional_alpha(g: &Ggx, w: Vec3A) -> f32 {
    if g.alpha_x == g.alpha_y {
        return g.alpha_x;
    }
    let (ax, ay) = (g.alpha_x * w.x, g.alpha_y * w.y);
    let rms2 = (g.alpha_x * g.alpha_x + g.alpha_y * g.alpha_y) / 2.0;
    (ax * ax + ay * ay + w.z * w.z * rms2).sqrt()
}

/// The smaller alpha of `g`: where the directional alpha misjudges (glass, and
/// reflection with total internal reflection, whose losses depend on the slopes in
/// every plane), anisotropic lobes read the isotropic tables here, which compensates
/// less than the lobe loses but never creates energy.
pub fn min_alpha(g: &Ggx) -> f32 {
    g.alpha_x.min(g.alpha_y)
}

/// Albedo of single-scattering GGX reflection with F = 1 from `mu` = cos θo.
pub fn ggx_e(mu: f32, alpha: f32) -> f32 {
    bilinear(&t::GGX_E, N_2D, alpha_coord(alpha), mu)
}

/// Its cosine-weighted average 2∫E(μ)μ dμ.
pub fn ggx_e_avg(alpha: f32) -> f32 {
    linear(&t::GGX_E_AVG, N_2D, alpha_coord(alpha))
}

/// Albedo of single-scattering GGX reflection off a dielectric of relative index
/// `eta` (inside / outside; below 1 seen from the denser side), exact unpolarised
/// Fresnel.
pub fn dielectric_e(mu: f32, alpha: f32, eta: f32) -> f32 {
    let (z, exit) = eta_coord(eta);
    let table: &[f32] = if exit {
        &t::DIELECTRIC_E_EXIT
    } else {
        &t::DIELECTRIC_E_ENTER
    };
    trilinear(table, N_3D, z, alpha_coord(alpha), mu)
}

/// Its cosine-weighted average.
pub fn dielectric_e_avg(alpha: f32, eta: f32) -> f32 {
    let (z, exit) = eta_coord(eta);
    let table: &[f32] = if exit {
        &t::DIELECTRIC_E_AVG_EXIT
    } else {
        &t::DIELECTRIC_E_AVG_ENTER
    };
    bilinear(table, N_3D, z, alpha_coord(alpha))
}

/// The cosine-weighted average of the dielectric's Fresnel reflectance, 2∫F(μ)μ dμ.
pub fn dielectric_f_avg(eta: f32) -> f32 {
    let (z, exit) = eta_coord(eta);
    let table: &[f32] = if exit {
        &t::DIELECTRIC_F_AVG_EXIT
    } else {
        &t::DIELECTRIC_F_AVG_ENTER
    };
    linear(table, N_3D, z)
}

/// Albedo of single-scattering rough glass, reflection plus transmission with the
/// 1/η² radiance compression left out (1 for a lossless interface), from the side
/// where the relative index is `eta` (> 1 entering, < 1 exiting).
pub fn glass_e(mu: f32, alpha: f32, eta: f32) -> f32 {
    let (z, exit) = eta_coord(eta);
    let table: &[f32] = if exit {
        &t::GLASS_E_EXIT
    } else {
        &t::GLASS_E_ENTER
    };
    trilinear(table, N_3D, z, alpha_coord(alpha), mu)
}

/// Its cosine-weighted average.
pub fn glass_e_avg(alpha: f32, eta: f32) -> f32 {
    let (z, exit) = eta_coord(eta);
    let table: &[f32] = if exit {
        &t::GLASS_E_AVG_EXIT
    } else {
        &t::GLASS_E_AVG_ENTER
    };
    bilinear(table, N_3D, z, alpha_coord(alpha))
}

/// The generator of `albedo_tables.rs` and the integrals the tests recompute.
#[cfg(test)]
pub(super) mod generator {
    use super::super::fresnel::{fresnel_dielectric, reflect, refract};
    use super::*;
    use glam::Vec2;
    use std::fmt::Write;

    /// What is integrated.
    #[derive(Clone, Copy, Debug)]
    pub enum Kind {
        /// GGX reflection with F = 1.
        White,
        /// Reflection off a dielectric of relative index η.
        Dielectric(f32),
        /// Glass: reflection plus transmission (η² compression left out).
        Glass(f32),
    }

    /// μ of table node `i` (μ = 0 is read as 10⁻³: the albedo's limit there).
    pub fn node_mu(i: usize, n: usize) -> f32 {
        (i as f32 / (n - 1) as f32).max(1e-3)
    }
    pub fn node_alpha(j: usize, n: usize) -> f32 {
        (j as f32 / (n - 1) as f32).powi(2)
    }
    pub fn node_eta(k: usize, n: usize) -> f32 {
        axis_to_eta(k as f32 / (n - 1) as f32)
    }

    /// f·cos/pdf of the visible normal `m` drawn for `wo` (Heitz 2018's estimator).
    pub fn weight(kind: Kind, g: &Ggx, wo: Vec3A, m: Vec3A) -> f64 {
        let g1 = g.g1(wo) as f64;
        let reflected = |f: f32| {
            let wi = reflect(wo, m);
            if wi.z > 0.0 {
                f as f64 * g.g(wo, wi) as f64 / g1
            } else {
                0.0
            }
        };
        match kind {
            Kind::White => reflected(1.0),
            Kind::Dielectric(eta) => reflected(fresnel_dielectric(wo.dot(m), eta)),
            Kind::Glass(eta) => {
                let f = fresnel_dielectric(wo.dot(m), eta);
                let t = match refract(wo, m, eta) {
                    Some(wt) if wt.z < 0.0 => (1.0 - f) as f64 * g.g(wo, wt) as f64 / g1,
                    _ => 0.0,
                };
                reflected(f) + t
            }
        }
    }

    /// Independent jittered-grid estimates per entry: their spread gives the error.
    pub const REPLICAS: usize = 8;

    /// The albedo and its standard error: [`REPLICAS`] independent estimates, each on an
    /// `n`×`n` jittered grid of the visible-normal sampler's unit square (stratified, so
    /// the TIR edge and the horizon, where the integrand jumps, cost little accuracy).
    pub fn integrate(kind: Kind, mu: f32, alpha: f32, n: usize, seed: u64) -> (f64, f64) {
        let wo = Vec3A::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        integrate_dir(kind, &Ggx::isotropic(alpha), wo, n, seed)
    }

    /// [`integrate`] for any distribution and direction.
    pub fn integrate_dir(kind: Kind, g: &Ggx, wo: Vec3A, n: usize, seed: u64) -> (f64, f64) {
        let mut rng = crate::sampling::Rng::for_sample(seed, 0, 0);
        let mut est = [0.0f64; REPLICAS];
        for e in &mut est {
            let mut sum = 0.0;
            for a in 0..n {
                for b in 0..n {
                    let j = rng.next_2d();
                    let u = Vec2::new(
                        ((a as f32 + j.x) / n as f32).min(1.0 - f32::EPSILON),
                        ((b as f32 + j.y) / n as f32).min(1.0 - f32::EPSILON),
                    );
                    sum += weight(kind, g, wo, g.sample_visible(wo, u));
                }
            }
            *e = sum / (n * n) as f64;
        }
        let k = REPLICAS as f64;
        let mean = est.iter().sum::<f64>() / k;
        let var = est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (k - 1.0);
        (mean, (var / k).sqrt())
    }

    /// Cosine-weighted average 2∫E(μ)μ dμ of the table row's linear interpolant (so
    /// that the interpolated E and E_avg agree exactly).
    pub fn row_average(row: &[f32]) -> f32 {
        let n = row.len();
        let sub = 64;
        let mut s = 0.0f64;
        for i in 0..(n - 1) * sub {
            let mu = (i as f64 + 0.5) / ((n - 1) * sub) as f64;
            let (k, t) = coord(mu as f32, n);
            let e = lerp(row[k], row[k + 1], t) as f64;
            s += 2.0 * e * mu / ((n - 1) * sub) as f64;
        }
        s as f32
    }

    /// 2∫F(μ)μ dμ of the dielectric's Fresnel reflectance (midpoint rule).
    pub fn fresnel_average(eta: f32) -> f32 {
        let n = 4096;
        let mut s = 0.0f64;
        for i in 0..n {
            let mu = (i as f64 + 0.5) / n as f64;
            s += 2.0 * fresnel_dielectric(mu as f32, eta) as f64 * mu / n as f64;
        }
        s as f32
    }

    /// Table of `kind()` over (√α, μ) and its largest standard error.
    fn table_2d(kind: impl Fn() -> Kind, n: usize, grid: usize, seed: u64) -> (Vec<f32>, f64) {
        let mut out = Vec::with_capacity(n * n);
        let mut err: f64 = 0.0;
        for j in 0..n {
            for i in 0..n {
                let (mu, alpha) = (node_mu(i, n), node_alpha(j, n));
                let s = seed * 10_000 + (j * n + i) as u64;
                let (e, se) = integrate(kind(), mu, alpha, grid, s);
                err = err.max(se);
                out.push(e as f32);
            }
        }
        (out, err)
    }

    fn averages(table: &[f32], n: usize) -> Vec<f32> {
        table.chunks(n).map(row_average).collect()
    }

    fn write_array(out: &mut String, name: &str, doc: &str, v: &[f32]) {
        writeln!(out, "/// {doc}").unwrap();
        writeln!(
            out,
            "#[rustfmt::skip]\npub static {name}: [f32; {}] = [",
            v.len()
        )
        .unwrap();
        for chunk in v.chunks(8) {
            let line: Vec<String> = chunk.iter().map(|x| format!("{x:.6}")).collect();
            writeln!(out, "    {},", line.join(", ")).unwrap();
        }
        writeln!(out, "];").unwrap();
    }

    /// The text of `albedo_tables.rs`, each entry from [`REPLICAS`] jittered `grid`²
    /// grids.
    pub fn generate(grid: usize) -> String {
        let mut out = String::new();
        let mut errors = Vec::new();
        writeln!(
            out,
            "//! Generated by `cargo test -p lightpath --lib \
             material::tests::generate_albedo_tables -- --ignored` (see albedo.rs); \
             do not edit.\n//! Each entry: the mean of {REPLICAS} estimates on jittered \
             {grid}×{grid} grids of visible-normal samples.\n"
        )
        .unwrap();
        let (e, err) = table_2d(|| Kind::White, N_2D, grid, 1);
        errors.push(err);
        write_array(&mut out, "GGX_E", "E(μ, α), F = 1: [√α][μ].", &e);
        write_array(
            &mut out,
            "GGX_E_AVG",
            "E_avg(α), F = 1: [√α].",
            &averages(&e, N_2D),
        );
        for (side, flip) in [("ENTER", false), ("EXIT", true)] {
            let eta_of = |k: usize| {
                let e = node_eta(k, N_3D);
                if flip {
                    1.0 / e
                } else {
                    e
                }
            };
            let fresnel: Vec<f32> = (0..N_3D).map(|k| fresnel_average(eta_of(k))).collect();
            for (name, glass) in [("DIELECTRIC", false), ("GLASS", true)] {
                let mut all = Vec::new();
                for k in 0..N_3D {
                    let eta = eta_of(k);
                    let kind = || {
                        if glass {
                            Kind::Glass(eta)
                        } else {
                            Kind::Dielectric(eta)
                        }
                    };
                    let seed = 2 + 100 * u64::from(flip) + 20 * u64::from(glass) + k as u64;
                    let (tab, err) = table_2d(kind, N_3D, grid, seed);
                    errors.push(err);
                    all.extend(tab);
                }
                let what = if glass {
                    "glass, reflection + transmission"
                } else {
                    "dielectric reflection"
                };
                write_array(
                    &mut out,
                    &format!("{name}_E_{side}"),
                    &format!("E(μ, α, η) of {what}, {side}: [η][√α][μ]."),
                    &all,
                );
                write_array(
                    &mut out,
                    &format!("{name}_E_AVG_{side}"),
                    &format!("E_avg(α, η) of {what}, {side}: [η][√α]."),
                    &averages(&all, N_3D),
                );
            }
            write_array(
                &mut out,
                &format!("DIELECTRIC_F_AVG_{side}"),
                &format!("F_avg(η) of the dielectric Fresnel, {side}: [η]."),
                &fresnel,
            );
        }
        let max = errors.iter().copied().fold(0.0, f64::max);
        writeln!(
            out,
            "/// Five times the largest standard error of an entry: the error the tests allow\n\
             /// an entry.\n#[cfg(test)]\npub const GENERATOR_ERROR: f32 = {:.6};",
            5.0 * max + 1e-6
        )
        .unwrap();
        out
    }
}
