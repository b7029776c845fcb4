//! Intel Embree 3 behind the accelerator's `intersect` / `occluded` seam (feature
//! `embree`, `--accel embree`): a yardstick for our own BVH, and for users who have the
//! library. Built from an [`Accel`] that is already built (its primitives, objects,
//! visibility and instances), so everything above the seam is unchanged: a hit is the
//! same (slot, distance, instanced slot) triple the BVH finds, and the surface at it is
//! computed by the same code.
//!
//! The raw C API of the `embree3` crate's `sys` module is used rather than its safe
//! layer, whose callbacks go through a per-geometry closure table: what is measured is
//! Embree's traversal, not a wrapper's.
//!
//! How the scene maps onto Embree:
//! - triangles go to triangle geometries, one per (object, visibility), three vertices a
//!   triangle (not shared: the BVH's primitives are triangles, not meshes);
//! - spheres to user geometries (bounds and the ray test are `Prim`'s own, so a sphere
//!   hit is the same distance as the BVH's);
//! - each placement of a shared mesh to an instance geometry of that mesh's own Embree
//!   scene, built once per mesh;
//! - which ray kinds see a primitive (`Visibility`) to the geometry's ray mask;
//! - the object a ray ignores (a shadow ray's light; the boundary a ray just passed, for
//!   what coincides with it) to a context filter function, set only on rays that ignore
//!   one.

use super::accel::{Accel, Visibility};
use super::{Prim, Ray};
use crate::error::AccelError;
use embree3::sys::*;
use std::collections::HashMap;
use std::ffi::c_void;
use std::sync::OnceLock;

/// The process's Embree device (created on first use, never released: Embree's worker
/// threads live as long as the process).
struct Device(RTCDevice);
// SAFETY: an Embree device handle may be used from any thread.
unsafe impl Send for Device {}
unsafe impl Sync for Device {}

fn device() -> Result<RTCDevice, AccelError> {
    static DEVICE: OnceLock<Result<Device, AccelError>> = OnceLock::new();
    let made = DEVICE.get_or_init(|| {
        // SAFETY: a null configuration string asks for the defaults.
        let device = unsafe { rtcNewDevice(std::ptr::null()) };
        if device.is_null() {
            return Err(AccelError::Embree(
                "Embree could not create a device (rtcNewDevice failed: does this CPU \
                 have SSE2?)"
                    .into(),
            ));
        }
        // SAFETY: `device` is a live device.
        let masks = unsafe { rtcGetDeviceProperty(device, RTCDeviceProperty::RAY_MASK_SUPPORTED) };
        let filters =
            unsafe { rtcGetDeviceProperty(device, RTCDeviceProperty::FILTER_FUNCTION_SUPPORTED) };
        if masks == 0 || filters == 0 {
            return Err(AccelError::Embree(
                "this Embree library was built without ray masks or filter functions \
                 (EMBREE_RAY_MASK, EMBREE_FILTER_FUNCTION), which --accel embree needs"
                    .into(),
            ));
        }
        Ok(Device(device))
    });
    made.as_ref().map(|d| d.0).map_err(Clone::clone)
}

/// The intersection context of one query: Embree's, then what the filter and the user
/// geometries read (the pointer Embree passes them is this struct's first field).
#[repr(C)]
struct Context {
    base: RTCIntersectContext,
    /// The object a ray ignores, or `u32::MAX`.
    ignore: u32,
    /// Object of each top-level geometry (the scene's `geom_object`).
    objects: *const u32,
}

impl Context {
    fn new(ignore: u32, objects: &[u32]) -> Context {
        Context {
            base: RTCIntersectContext {
                flags: RTCIntersectContextFlags::INCOHERENT,
                filter: if ignore == u32::MAX {
                    None
                } else {
                    Some(ignore_filter)
                },
                instID: [RTC_INVALID_GEOMETRY_ID],
            },
            ignore,
            objects: objects.as_ptr(),
        }
    }

    /// The object of a hit on geometry `geom` (of the instanced mesh when `inst` is valid:
    /// then the placement's object).
    ///
    /// # Safety
    /// `inst` (when valid) or `geom` is a geometry id of the top-level scene that made
    /// `objects`.
    unsafe fn object(&self, geom: u32, inst: u32) -> u32 {
        let top = if inst == RTC_INVALID_GEOMETRY_ID {
            geom
        } else {
            inst
        };
        *self.objects.add(top as usize)
    }
}

const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;

/// Rejects hits on the ignored object (a shadow ray's light, a boundary just passed).
unsafe extern "C" fn ignore_filter(args: *const RTCFilterFunctionNArguments) {
    let args = &*args;
    let context = &*(args.context as *const Context);
    let n = args.N as usize;
    let hit = args.hit as *const u32;
    for i in 0..n {
        let valid = args.valid.add(i);
        if *valid == 0 {
            continue;
        }
        // RTCHitN: Ng x, y, z, u, v, primID, geomID, instID[0], each N wide.
        let geom = *hit.add(6 * n + i);
        let inst = *hit.add(7 * n + i);
        if context.object(geom, inst) == context.ignore {
            *valid = 0;
        }
    }
}

/// What a user geometry (spheres of one object and visibility) holds.
struct Spheres {
    prims: Vec<Prim>,
    visibility: u32,
}

unsafe extern "C" fn sphere_bounds(args: *const RTCBoundsFunctionArguments) {
    let args = &*args;
    let spheres = &*(args.geometryUserPtr as *const Spheres);
    let (lo, hi) = spheres.prims[args.primID as usize].bounds();
    *args.bounds_o = RTCBounds {
        lower_x: lo.x,
        lower_y: lo.y,
        lower_z: lo.z,
        align0: 0.0,
        upper_x: hi.x,
        upper_y: hi.y,
        upper_z: hi.z,
        align1: 0.0,
    };
}

/// Ray fields in Embree's SOA layout (`RTCRayN`, then `RTCHitN` for a ray with its hit):
/// field `f` of ray `i` of `n` is word `f * n + i`.
const ORG: usize = 0;
const TNEAR: usize = 3;
const DIR: usize = 4;
const TFAR: usize = 8;
const MASK: usize = 9;
const HIT_PRIM: usize = 12 + 5;
const HIT_GEOM: usize = 12 + 6;
const HIT_INST: usize = 12 + 7;

/// The ray `i` of `n` at `words` (origin, direction, tnear, tfar, mask).
unsafe fn ray_at(
    words: *const f32,
    n: usize,
    i: usize,
) -> (glam::Vec3A, glam::Vec3A, f32, f32, u32) {
    let w = |f: usize| *words.add(f * n + i);
    (
        glam::Vec3A::new(w(ORG), w(ORG + 1), w(ORG + 2)),
        glam::Vec3A::new(w(DIR), w(DIR + 1), w(DIR + 2)),
        w(TNEAR),
        w(TFAR),
        w(MASK).to_bits(),
    )
}

unsafe extern "C" fn sphere_intersect(args: *const RTCIntersectFunctionNArguments) {
    let args = &*args;
    let spheres = &*(args.geometryUserPtr as *const Spheres);
    let context = &*(args.context as *const Context);
    let prim = &spheres.prims[args.primID as usize];
    let n = args.N as usize;
    let words = args.rayhit as *mut f32;
    for i in 0..n {
        if *args.valid.add(i) == 0 {
            continue;
        }
        let (o, d, tnear, tfar, mask) = ray_at(words, n, i);
        if mask & spheres.visibility == 0
            || (context.ignore != u32::MAX
                && context.object(args.geomID, context.base.instID[0]) == context.ignore)
        {
            continue;
        }
        let t = prim.intersect(o, d, tnear, tfar);
        if t < tfar {
            *words.add(TFAR * n + i) = t;
            let w = words as *mut u32;
            *w.add(HIT_PRIM * n + i) = args.primID;
            *w.add(HIT_GEOM * n + i) = args.geomID;
            *w.add(HIT_INST * n + i) = context.base.instID[0];
        }
    }
}

unsafe extern "C" fn sphere_occluded(args: *const RTCOccludedFunctionNArguments) {
    let args = &*args;
    let spheres = &*(args.geometryUserPtr as *const Spheres);
    let context = &*(args.context as *const Context);
    let prim = &spheres.prims[args.primID as usize];
    let n = args.N as usize;
    let words = args.ray as *mut f32;
    for i in 0..n {
        if *args.valid.add(i) == 0 {
            continue;
        }
        let (o, d, tnear, tfar, mask) = ray_at(words, n, i);
        if mask & spheres.visibility == 0
            || (context.ignore != u32::MAX
                && context.object(args.geomID, context.base.instID[0]) == context.ignore)
        {
            continue;
        }
        if prim.intersect(o, d, tnear, tfar).is_finite() {
            // Embree's mark of an occluded ray.
            *words.add(TFAR * n + i) = f32::NEG_INFINITY;
        }
    }
}

/// One Embree scene over an accelerator's primitives.
pub struct EmbreeScene {
    handle: RTCScene,
    /// Object of each geometry, by geometry id.
    geom_object: Vec<u32>,
    /// Each geometry's primitives' slots in the accelerator: `geom_slots[geom_first[g] +
    /// prim]`; an instance geometry's one entry is its `Prim::Instance`'s slot.
    geom_first: Vec<u32>,
    geom_slots: Vec<u32>,
    /// The mesh an instance geometry places (index into `meshes`), `u32::MAX` for others.
    geom_mesh: Vec<u32>,
    /// The shared meshes' scenes (instances name them); kept alive with this one.
    meshes: Vec<EmbreeScene>,
    /// The user geometries' data, read by the callbacks while `handle` lives; boxed so
    /// that the addresses Embree holds stay put while the list grows.
    #[allow(clippy::vec_box)]
    _spheres: Vec<Box<Spheres>>,
}

// SAFETY: a committed Embree scene may be queried from any number of threads at once; the
// callbacks' data is only read.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: `handle` is this scene's one reference (the instances of the mesh scenes
        // hold theirs, which Embree releases with this scene, before `meshes` drop).
        unsafe { rtcReleaseScene(self.handle) };
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Kind {
    Triangles,
    Spheres,
}

impl EmbreeScene {
    /// An Embree scene over `accel`'s primitives (and its meshes'), `visibility` each
    /// slot's ray kinds. In a shared mesh (`inner`) every primitive that some ray kind
    /// sees is seen by all: the placement's visibility decides (as in the BVH).
    pub fn build(accel: &Accel, visibility: &[u8], inner: bool) -> Result<EmbreeScene, AccelError> {
        let meshes = accel
            .meshes()
            .iter()
            .map(|m| EmbreeScene::build(m, m.visibility(), true))
            .collect::<Result<Vec<_>, _>>()?;
        let device = device()?;
        // SAFETY: a live device; every handle made below is checked and released.
        unsafe {
            let handle = rtcNewScene(device);
            if handle.is_null() {
                return Err(error(device, "rtcNewScene"));
            }
            rtcSetSceneFlags(handle, RTCSceneFlags::CONTEXT_FILTER_FUNCTION);
            let mut scene = EmbreeScene {
                handle,
                geom_object: Vec::new(),
                geom_first: Vec::new(),
                geom_slots: Vec::new(),
                geom_mesh: Vec::new(),
                meshes,
                _spheres: Vec::new(),
            };
            let prims = accel.prims();
            // Triangles and spheres grouped by (kind, object, visibility), in slot order.
            let mut groups: HashMap<(Kind, u32, u8), usize> = HashMap::new();
            let mut members: Vec<(Kind, u32, u8, Vec<u32>)> = Vec::new();
            let mut instances = Vec::new();
            for (slot, prim) in prims.iter().enumerate() {
                let vis = visibility[slot];
                if vis == 0 {
                    continue;
                }
                let object = accel.object_of(slot as u32);
                let kind = match prim {
                    Prim::Triangle { .. } => Kind::Triangles,
                    // User geometry: `Prim::intersect` tests them.
                    Prim::Sphere { .. } | Prim::Cylinder { .. } => Kind::Spheres,
                    Prim::Instance { index, .. } => {
                        instances.push((slot as u32, *index, object, vis));
                        continue;
                    }
                };
                let g = *groups.entry((kind, object, vis)).or_insert_with(|| {
                    members.push((kind, object, vis, Vec::new()));
                    members.len() - 1
                });
                members[g].3.push(slot as u32);
            }
            for (kind, object, vis, slots) in members {
                let geom = match kind {
                    Kind::Triangles => triangles(device, prims, &slots)?,
                    Kind::Spheres => {
                        let data = Box::new(Spheres {
                            prims: slots.iter().map(|&s| prims[s as usize]).collect(),
                            visibility: if inner { u32::MAX } else { vis as u32 },
                        });
                        let geom = spheres(device, &data)?;
                        scene._spheres.push(data);
                        geom
                    }
                };
                let mask = if inner { u32::MAX } else { vis as u32 };
                scene.attach(geom, mask, object, &slots, u32::MAX)?;
            }
            for (slot, index, object, vis) in instances {
                let inst = &accel.instances()[index as usize];
                let mesh = &scene.meshes[inst.mesh as usize];
                let geom = rtcNewGeometry(device, RTCGeometryType::INSTANCE);
                if geom.is_null() {
                    return Err(error(device, "rtcNewGeometry(INSTANCE)"));
                }
                rtcSetGeometryInstancedScene(geom, mesh.handle);
                // Column-major 3×4: the three axes, then the translation.
                let m = inst.to_world;
                let xfm: [f32; 12] = [
                    m.matrix3.x_axis.x,
                    m.matrix3.x_axis.y,
                    m.matrix3.x_axis.z,
                    m.matrix3.y_axis.x,
                    m.matrix3.y_axis.y,
                    m.matrix3.y_axis.z,
                    m.matrix3.z_axis.x,
                    m.matrix3.z_axis.y,
                    m.matrix3.z_axis.z,
                    m.translation.x,
                    m.translation.y,
                    m.translation.z,
                ];
                rtcSetGeometryTransform(
                    geom,
                    0,
                    RTCFormat::FLOAT3X4_COLUMN_MAJOR,
                    xfm.as_ptr() as *const c_void,
                );
                scene.attach(geom, vis as u32, object, &[slot], inst.mesh)?;
            }
            rtcCommitScene(handle);
            let err = rtcGetDeviceError(device);
            if err != RTCError::NONE {
                return Err(AccelError::Embree(format!(
                    "Embree could not build the scene ({err:?})"
                )));
            }
            Ok(scene)
        }
    }

    /// Commits `geom` and attaches it with ray mask `mask`, recording its primitives.
    unsafe fn attach(
        &mut self,
        geom: RTCGeometry,
        mask: u32,
        object: u32,
        slots: &[u32],
        mesh: u32,
    ) -> Result<(), AccelError> {
        rtcSetGeometryMask(geom, mask);
        rtcCommitGeometry(geom);
        let id = rtcAttachGeometry(self.handle, geom);
        rtcReleaseGeometry(geom);
        if id as usize != self.geom_object.len() {
            return Err(AccelError::Embree(format!(
                "Embree numbered geometry {} as {id}",
                self.geom_object.len()
            )));
        }
        self.geom_object.push(object);
        self.geom_first.push(self.geom_slots.len() as u32);
        self.geom_slots.extend_from_slice(slots);
        self.geom_mesh.push(mesh);
        Ok(())
    }

    #[inline]
    fn slot(&self, geom: u32, prim: u32) -> u32 {
        self.geom_slots[(self.geom_first[geom as usize] + prim) as usize]
    }

    /// The nearest hit among primitives rays of kind `mask` see, other than object
    /// `ignore`'s: (slot, t, the instanced mesh's slot or `u32::MAX`), as the BVH's
    /// `nearest`; `None` for a miss.
    #[inline]
    pub fn intersect(
        &self,
        ray: &Ray,
        tmin: f32,
        mask: u8,
        ignore: u32,
    ) -> Option<(u32, f32, u32)> {
        let mut context = Context::new(ignore, &self.geom_object);
        let mut rayhit = RTCRayHit {
            ray: rtc_ray(ray, tmin, mask),
            hit: RTCHit {
                Ng_x: 0.0,
                Ng_y: 0.0,
                Ng_z: 0.0,
                u: 0.0,
                v: 0.0,
                primID: RTC_INVALID_GEOMETRY_ID,
                geomID: RTC_INVALID_GEOMETRY_ID,
                instID: [RTC_INVALID_GEOMETRY_ID],
            },
        };
        // SAFETY: a committed scene; the context's first field is Embree's context.
        unsafe { rtcIntersect1(self.handle, &mut context.base, &mut rayhit) };
        let hit = rayhit.hit;
        if hit.geomID == RTC_INVALID_GEOMETRY_ID {
            return None;
        }
        let t = rayhit.ray.tfar;
        let inst = hit.instID[0];
        Some(if inst == RTC_INVALID_GEOMETRY_ID {
            (self.slot(hit.geomID, hit.primID), t, u32::MAX)
        } else {
            let mesh = &self.meshes[self.geom_mesh[inst as usize] as usize];
            (self.slot(inst, 0), t, mesh.slot(hit.geomID, hit.primID))
        })
    }

    /// Is anything that casts shadows between the origin and `tmax`, other than object
    /// `ignore`? As the BVH's `occluded`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmin: f32, ignore: u32) -> bool {
        let mut context = Context::new(ignore, &self.geom_object);
        let mut ray = rtc_ray(ray, tmin, Visibility::SHADOW);
        // SAFETY: a committed scene; the context's first field is Embree's context.
        unsafe { rtcOccluded1(self.handle, &mut context.base, &mut ray) };
        ray.tfar == f32::NEG_INFINITY
    }
}

fn rtc_ray(ray: &Ray, tmin: f32, mask: u8) -> RTCRay {
    RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: tmin,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar: ray.tmax,
        mask: mask as u32,
        id: 0,
        flags: 0,
    }
}

/// Embree's last error, named with the call that failed.
unsafe fn error(device: RTCDevice, call: &str) -> AccelError {
    AccelError::Embree(format!(
        "Embree: {call} failed ({:?})",
        rtcGetDeviceError(device)
    ))
}

/// A triangle geometry over the triangles at `slots`.
unsafe fn triangles(
    device: RTCDevice,
    prims: &[Prim],
    slots: &[u32],
) -> Result<RTCGeometry, AccelError> {
    let geom = rtcNewGeometry(device, RTCGeometryType::TRIANGLE);
    if geom.is_null() {
        return Err(error(device, "rtcNewGeometry(TRIANGLE)"));
    }
    let n = slots.len();
    let vertices =
        rtcSetNewGeometryBuffer(geom, RTCBufferType::VERTEX, 0, RTCFormat::FLOAT3, 12, 3 * n)
            as *mut [f32; 3];
    let indices = rtcSetNewGeometryBuffer(geom, RTCBufferType::INDEX, 0, RTCFormat::UINT3, 12, n)
        as *mut [u32; 3];
    if vertices.is_null() || indices.is_null() {
        rtcReleaseGeometry(geom);
        return Err(error(device, "rtcSetNewGeometryBuffer"));
    }
    let vertices = std::slice::from_raw_parts_mut(vertices, 3 * n);
    let indices = std::slice::from_raw_parts_mut(indices, n);
    for (k, &slot) in slots.iter().enumerate() {
        let Prim::Triangle { p0, e1, e2, .. } = prims[slot as usize] else {
            unreachable!("triangle groups hold triangles")
        };
        let (p1, p2) = (p0 + e1, p0 + e2);
        vertices[3 * k] = p0.to_array();
        vertices[3 * k + 1] = p1.to_array();
        vertices[3 * k + 2] = p2.to_array();
        let base = 3 * k as u32;
        indices[k] = [base, base + 1, base + 2];
    }
    Ok(geom)
}

/// A user geometry over the spheres in `data`.
unsafe fn spheres(device: RTCDevice, data: &Spheres) -> Result<RTCGeometry, AccelError> {
    let geom = rtcNewGeometry(device, RTCGeometryType::USER);
    if geom.is_null() {
        return Err(error(device, "rtcNewGeometry(USER)"));
    }
    rtcSetGeometryUserPrimitiveCount(geom, data.prims.len() as u32);
    rtcSetGeometryUserData(geom, data as *const Spheres as *mut c_void);
    rtcSetGeometryBoundsFunction(geom, Some(sphere_bounds), std::ptr::null_mut());
    rtcSetGeometryIntersectFunction(geom, Some(sphere_intersect));
    rtcSetGeometryOccludedFunction(geom, Some(sphere_occluded));
    Ok(geom)
}
