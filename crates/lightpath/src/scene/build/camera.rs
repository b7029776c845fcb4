//! The camera, pixel filter and render settings.

use crate::camera::{Camera, PixelFilter};
use crate::scene::desc::{CameraDesc, FilterDesc, Origin, SceneDesc};
use crate::scene::{RenderSettings, SceneError};
use glam::Vec3A;

pub fn camera(desc: &SceneDesc) -> Result<Camera, SceneError> {
    let [w, h] = desc.film.resolution;
    if w == 0 || h == 0 {
        return Err(Origin::file(&desc.source).error("film resolution must be at least 1x1"));
    }
    let default_camera = CameraDesc {
        origin: Origin::file(&desc.source),
        ..CameraDesc::default()
    };
    let c = desc.camera.as_ref().unwrap_or(&default_camera);
    let v3 = Vec3A::from;
    let vectors = [c.position, c.look_at, c.up];
    let mut numbers = vectors
        .iter()
        .flatten()
        .chain([&c.aperture_radius])
        .chain(c.focus_distance.as_ref());
    if numbers.any(|v| !v.is_finite()) || c.aperture_radius < 0.0 {
        return Err(c.origin.error(
            "[camera]: position, look_at, up, aperture_radius and focus_distance must be \
             finite (and the aperture not negative)",
        ));
    }
    if let FilterDesc::Gaussian { stddev } = desc.film.filter {
        if !(stddev > 0.0 && stddev.is_finite()) {
            return Err(Origin::file(&desc.source).error(format!(
                "[film]: filter_stddev must be a positive number, got {stddev}"
            )));
        }
    }
    let position = v3(c.position);
    let look_at = v3(c.look_at);
    let forward = look_at - position;
    if !forward.is_finite() || forward.length() < 1e-9 {
        return Err(c
            .origin
            .error("[camera]: look_at must differ from position"));
    }
    if v3(c.up).cross(forward).length() < 1e-9 * forward.length() {
        return Err(c
            .origin
            .error("[camera]: up must not point along the view direction"));
    }
    if !(c.fov > 0.0 && c.fov < 180.0) {
        return Err(c.origin.error(format!(
            "[camera]: fov must be between 0 and 180 degrees, got {}",
            c.fov
        )));
    }
    Ok(Camera::new(
        position,
        look_at,
        v3(c.up),
        c.fov,
        c.fov_axis,
        w,
        h,
        c.aperture_radius,
        c.focus_distance.unwrap_or((look_at - position).length()),
    ))
}

pub fn filter(desc: &SceneDesc) -> PixelFilter {
    match desc.film.filter {
        FilterDesc::Box => PixelFilter::Box,
        FilterDesc::Gaussian { stddev } => PixelFilter::Gaussian { stddev },
    }
}

pub fn settings(desc: &SceneDesc) -> RenderSettings {
    let r = &desc.render;
    RenderSettings {
        spp: r.spp.max(1),
        max_depth: r.max_depth,
        max_diffuse_depth: r.max_diffuse_depth.unwrap_or(u32::MAX),
        max_specular_depth: r.max_specular_depth.unwrap_or(u32::MAX),
        rr_depth: r.rr_depth,
        clamp_direct: r.clamp_direct,
        clamp_indirect: r.clamp_indirect,
        seed: r.seed,
        sampler: r.sampler,
        light_selection: r.light_selection,
        noise_threshold: r.noise_threshold.max(0.0),
        min_spp: r.min_spp.max(1),
        regularize: r.regularize.clamp(0.0, 1.0),
    }
}
