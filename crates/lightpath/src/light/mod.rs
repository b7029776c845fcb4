//! Lights: one file per kind behind one interface, [`LightModel`], and [`LightShape`], the
//! closed set of kinds a [`Light`] stores inline (dispatch by `match`, no allocation, as
//! the material lobes are). Area lights: `triangles` (rectangle, quad, disk), `mesh` (an
//! object's own triangles), `sphere`, `cylinder`; delta lights: `point`, `spot`,
//! `distant`; at infinity: `dome`. `select` chooses which light a shading point samples;
//! `spherical_rect` samples rectangles in solid angle.
//!
//! A [`Light`] carries what is the same for every kind: its colour, its light groups, the
//! classes of its `L` and `O` events and its part in split AOVs, so that the integrator
//! asks the light and nothing beside it. Adding a kind is one file here and its name in
//! the `lights!` line below (docs/architecture.md has the recipe).
//!
//! ```toml
//! [[lights]]
//! type = "rect"            # rect | quad | disk | sphere | cylinder | point | spot | distant | dome | mesh
//! groups = ["key"]
//! radiance = [17, 12, 4]   # area and dome lights; point/spot: intensity; distant: irradiance
//! translate = [0, 0.99, 0]
//! rotate = [90, 0, 0]
//! scale = [0.25, 0.25, 1]
//! ```

pub mod cylinder;
pub mod distant;
pub mod dome;
pub mod mesh;
pub mod point;
pub mod portal;
pub mod select;
pub mod sphere;
pub mod spherical_rect;
pub mod spot;
pub mod triangles;

pub use cylinder::Cylinder;
pub use distant::Distant;
pub use dome::{Dome, EnvMap};
pub use mesh::Mesh;
pub use point::Point;
pub use select::Reach;
pub use sphere::Sphere;
pub use spot::Spot;
pub use triangles::Triangles;

use crate::geometry::{Prim, Ray};
use glam::{Vec2, Vec3A};
use lpe::ClassId;

pub fn luminance(c: Vec3A) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A light sample as seen from a shading point.
pub struct LightSample {
    /// Direction to the light.
    pub wi: Vec3A,
    /// Distance to the sampled point (infinite for distant and dome lights).
    pub dist: f32,
    /// Radiance arriving along `wi` (for delta lights: intensity / d², irradiance).
    pub radiance: Vec3A,
    /// Solid-angle pdf (not including the choice of the light); 1 for delta lights.
    pub pdf: f32,
    pub delta: bool,
}

/// The one light interface. `color` is the light's radiance (area, dome), intensity
/// (point, spot) or irradiance (distant); `c` its largest component, not negative.
/// `prims` is the scene's primitive list, which triangle lights index.
pub trait LightModel {
    /// A point of the light as seen from `p`, chosen with `u`, or `None` when the light
    /// cannot reach `p` (behind a one-sided emitter, outside a spot's cone). `n` is the
    /// receiver's shading normal (zero in a medium): rect lights warp their samples by
    /// its cosine (`spherical_rect.rs`), the others ignore it.
    fn sample(
        &self,
        color: Vec3A,
        p: Vec3A,
        n: Vec3A,
        u: Vec2,
        prims: &[Prim],
    ) -> Option<LightSample>;
    /// The solid-angle pdf with which `sample` from `p` with normal `n` would pick the
    /// point a ray along `dir` finds at distance `t` with normal `ng` (infinite `t` and
    /// zero `ng`: a ray that escaped). Zero for delta lights, which no ray finds.
    fn pdf(&self, p: Vec3A, n: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        let _ = (p, n, dir, t, ng);
        0.0
    }
    /// Radiance leaving the light's surface at a point with normal `ng` towards `-dir`
    /// (the direction of the ray that hit it); zero for lights without a surface.
    fn emitted(&self, color: Vec3A, ng: Vec3A, dir: Vec3A) -> Vec3A {
        let _ = (color, ng, dir);
        Vec3A::ZERO
    }
    /// Radiance arriving from `-dir` at a ray along `dir` that left the scene; zero but
    /// for lights that rays reach by escaping ([`escapes`](Self::escapes)).
    fn escaped(&self, color: Vec3A, dir: Vec3A) -> Vec3A {
        let _ = (color, dir);
        Vec3A::ZERO
    }
    /// Whether rays that leave the scene reach this light (a dome).
    fn escapes(&self) -> bool {
        false
    }
    /// Emitted power in the same unit for every kind (radiance × area × π for surfaces;
    /// for lights at infinity the power through the scene's cross-section of radius
    /// `scene_radius`, as pbrt-v4's `Phi`), by the colour's largest component `c`.
    fn power(&self, c: f32, scene_radius: f32) -> f32;
    /// What the light tree knows of the light: its bounds, or what it can deliver from
    /// infinity.
    fn reach(&self, c: f32, prims: &[Prim]) -> Reach;
    /// The nearest point of the light's surface along `ray` before `tmax`: its distance
    /// and normal, for the lights-only test of `unoccluded` and `shadows` AOVs. `None`
    /// for lights without a surface, and for mesh lights, which their own BVH finds.
    fn intersect(&self, ray: &Ray, tmax: f32, prims: &[Prim]) -> Option<(f32, Vec3A)> {
        let _ = (ray, tmax, prims);
        None
    }
    /// A Dirac light (point, spot, distant): light sampling alone finds it.
    fn is_delta(&self) -> bool {
        false
    }
    /// Whether the light's own surface may shadow it (a mesh's triangles one another):
    /// then shadow rays towards it do not pass through its object.
    fn shadows_itself(&self) -> bool {
        false
    }
}

macro_rules! lights {
    ($($kind:ident),* $(,)?) => {
        /// Every light kind; adding one is a new file plus its name here.
        #[derive(Clone, Debug)]
        pub enum LightShape {
            $($kind($kind),)*
        }

        impl LightModel for LightShape {
            #[inline]
            fn sample(&self, color: Vec3A, p: Vec3A, n: Vec3A, u: Vec2, prims: &[Prim]) -> Option<LightSample> {
                match self { $(LightShape::$kind(l) => l.sample(color, p, n, u, prims),)* }
            }
            #[inline]
            fn pdf(&self, p: Vec3A, n: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
                match self { $(LightShape::$kind(l) => l.pdf(p, n, dir, t, ng),)* }
            }
            #[inline]
            fn emitted(&self, color: Vec3A, ng: Vec3A, dir: Vec3A) -> Vec3A {
                match self { $(LightShape::$kind(l) => l.emitted(color, ng, dir),)* }
            }
            #[inline]
            fn escaped(&self, color: Vec3A, dir: Vec3A) -> Vec3A {
                match self { $(LightShape::$kind(l) => l.escaped(color, dir),)* }
            }
            fn escapes(&self) -> bool {
                match self { $(LightShape::$kind(l) => l.escapes(),)* }
            }
            fn power(&self, c: f32, scene_radius: f32) -> f32 {
                match self { $(LightShape::$kind(l) => l.power(c, scene_radius),)* }
            }
            fn reach(&self, c: f32, prims: &[Prim]) -> Reach {
                match self { $(LightShape::$kind(l) => l.reach(c, prims),)* }
            }
            #[inline]
            fn intersect(&self, ray: &Ray, tmax: f32, prims: &[Prim]) -> Option<(f32, Vec3A)> {
                match self { $(LightShape::$kind(l) => l.intersect(ray, tmax, prims),)* }
            }
            #[inline]
            fn is_delta(&self) -> bool {
                match self { $(LightShape::$kind(l) => l.is_delta(),)* }
            }
            #[inline]
            fn shadows_itself(&self) -> bool {
                match self { $(LightShape::$kind(l) => l.shadows_itself(),)* }
            }
        }

        $(impl From<$kind> for LightShape {
            fn from(l: $kind) -> LightShape {
                LightShape::$kind(l)
            }
        })*
    };
}

lights!(Triangles, Mesh, Sphere, Cylinder, Point, Spot, Distant, Dome);

/// The classes of a light's two events: `L` when a path reaches it after scattering,
/// `O` when the camera sees it. A glow's are both its object's `O` (events.rs sets them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightClasses {
    pub light: ClassId,
    pub seen: ClassId,
}

/// One light: its kind and what every kind has.
#[derive(Clone, Debug)]
pub struct Light {
    pub shape: LightShape,
    /// Radiance (area, dome), intensity (point, spot) or irradiance (distant).
    pub color: Vec3A,
    pub groups: Vec<String>,
    pub camera_visible: bool,
    /// The object the light's surface belongs to (area lights), if any.
    pub object: Option<u32>,
    /// A glowing object that light sampling picks (`scene/build/glows.rs`), not a light:
    /// its samples are `O` events with its object's labels, and what cannot reach it is
    /// no shadow.
    pub glow: bool,
    /// Its events' classes, set once the AOVs are compiled (`events.rs`).
    pub classes: LightClasses,
    /// Its part in AOVs split per light group: its first group's, or the default part
    /// after all groups (`scene/build/lights.rs::groups`).
    pub part: u32,
    /// Shadow linking: some objects cast no shadow from it (their `unshadowing`). Its
    /// light samples then take the whole weight (a BSDF ray stops at such an object and
    /// cannot find the light behind it).
    pub shadow_linked: bool,
}

impl Light {
    /// A declared light of `shape` and `color` (classes and part are set at build).
    pub fn new(shape: impl Into<LightShape>, color: Vec3A) -> Light {
        Light {
            shape: shape.into(),
            color,
            groups: Vec::new(),
            camera_visible: true,
            object: None,
            glow: false,
            classes: LightClasses::default(),
            part: 0,
            shadow_linked: false,
        }
    }

    pub fn is_delta(&self) -> bool {
        self.shape.is_delta()
    }

    /// Samples a point of the light as seen from `p` with shading normal `n` (zero in a
    /// medium); `prims` is the scene's primitive list, which area lights index.
    #[inline]
    pub fn sample(&self, p: Vec3A, n: Vec3A, u: Vec2, prims: &[Prim]) -> Option<LightSample> {
        self.shape.sample(self.color, p, n, u, prims)
    }

    /// The object a shadow ray towards this light may pass through: an area light's own
    /// surface (convex or planar, it cannot hide itself); none for a light whose surface
    /// may shadow itself.
    #[inline]
    pub fn shadow_exempt(&self) -> u32 {
        if self.shape.shadows_itself() {
            u32::MAX
        } else {
            self.object.unwrap_or(u32::MAX)
        }
    }

    /// Radiance leaving a point of the light's surface with normal `ng` towards `-dir`
    /// (the ray direction that hit it).
    #[inline]
    pub fn emitted_at(&self, ng: Vec3A, dir: Vec3A) -> Vec3A {
        self.shape.emitted(self.color, ng, dir)
    }

    /// Radiance of a dome arriving from direction `-dir` (a ray along `dir` escaped).
    #[inline]
    pub fn emitted_escaped(&self, dir: Vec3A) -> Vec3A {
        self.shape.escaped(self.color, dir)
    }

    /// The solid-angle pdf with which `sample` from `p` with normal `n` would pick the
    /// point hit at distance `t` along `dir` (normal `ng`).
    #[inline]
    pub fn pdf_hit(&self, p: Vec3A, n: Vec3A, dir: Vec3A, t: f32, ng: Vec3A) -> f32 {
        self.shape.pdf(p, n, dir, t, ng)
    }

    /// The colour's largest component, the scale of `power` and of the tree's bounds.
    fn scale(&self) -> f32 {
        self.color.max_element().max(0.0)
    }

    /// Emitted power (see [`LightModel::power`]).
    pub fn power(&self, scene_radius: f32) -> f32 {
        self.shape.power(self.scale(), scene_radius)
    }

    /// What the light tree knows of the light (see [`LightModel::reach`]).
    pub fn reach(&self, prims: &[Prim]) -> Reach {
        self.shape.reach(self.scale(), prims)
    }
}
