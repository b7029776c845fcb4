//! The camera, pixel filter and render settings.

use crate::camera::{Camera, PixelFilter};
use crate::scene::desc::{CameraDesc, Origin, SceneDesc};
use crate::scene::SceneError;
use crate::settings::RenderDesc;
use glam::Vec3A;

pub fn camera(desc: &SceneDesc) -> Result<Camera, SceneError> {
    let [w, h] = desc.render.resolution;
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
    PixelFilter::new(
        desc.render.filter,
        desc.render.filter_stddev,
        desc.render.filter_width,
    )
}

/// The settings, checked: a description built by code rather than read from a file
/// meets the same ranges (`settings.rs`) as one read from a file.
pub fn settings(desc: &SceneDesc) -> Result<RenderDesc, SceneError> {
    crate::settings::check(&desc.render).map_err(|e| Origin::file(&desc.source).error(e))?;
    Ok(desc.render.clone())
}
