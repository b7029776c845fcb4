//! SceneDesc → Scene, in small steps: materials, geometry (objects and the surfaces of
//! area lights), lights, the AOV automaton and every event's class, camera and settings.

pub mod camera;
pub mod geometry;
pub mod glows;
pub mod lights;
pub mod materials;
pub mod media;

use crate::aov::AovSpec;
use crate::events::Vocabulary;
use crate::geometry::Visibility;
use crate::light::select::LightSelector;
use crate::light::Light;
use crate::scene::desc::{LightDesc, LightKind, Origin, SceneDesc, ShapeDesc};
use crate::scene::{Aov, Object, Scene, SceneError};
use geometry::GeometryBuilder;
use glam::Vec3A;
use lpe::{Automaton, ClassId};
use std::collections::HashMap;
use std::ops::Range;

impl Scene {
    /// Builds a scene from its description and the AOVs to render (beauty first).
    pub fn build(desc: &SceneDesc, aovs: &[AovSpec]) -> Result<Scene, SceneError> {
        let settings = camera::settings(desc)?;
        let (materials, material_ids) = materials::build(desc)?;
        let mut geometry = GeometryBuilder::default();
        let (mut objects, object_prims) = add_objects(desc, &material_ids, &mut geometry)?;
        let (mut lights, light_prims) =
            add_lights(desc, &material_ids, &mut geometry, &mut objects)?;
        let (accel, surface) = geometry.build();
        lights::locate_prims(&mut lights, &light_prims, &accel);
        let mesh_lights = lights::mesh_surfaces(&mut lights, &desc.lights, &object_prims, &accel)?;
        lights::link(&desc.lights, &mut objects, &mut lights);
        let first_glow_light = lights.len();
        glows::add(
            &mut lights,
            &mut objects,
            &materials,
            &desc.objects,
            &object_prims,
            &accel,
        );
        let (scene_center, scene_radius, epsilon) = geometry::scene_size(&accel);
        let light_select = LightSelector::build(
            desc.render.light_selection,
            &lights,
            accel.prims(),
            scene_radius,
        );

        let (volumes, atmosphere) = media::build(desc, &mut objects)?;

        let vocabulary = Vocabulary::of_scene(&objects, &materials, &lights, atmosphere.is_some());
        let automaton = compile_aovs(desc, aovs, &vocabulary)?;
        let classes = vocabulary.classify(&automaton, &mut objects, &mut lights);
        let atmosphere = atmosphere.map(|volume| crate::scene::MediumUse {
            volume,
            scatter_class: classes.atmosphere_scatter,
            glow_class: classes.atmosphere_glow,
        });

        let camera = camera::camera(desc)?;
        let camera_media = media::media_at(camera.position, &accel, &objects, epsilon);
        let has_media = atmosphere.is_some()
            || objects
                .iter()
                .any(|o| o.interior.is_some() || o.null_surface);
        let has_presence = objects.iter().any(|o| {
            o.material
                .is_some_and(|m| materials[m as usize].presence.is_some())
        });
        let light_groups = lights::groups(&mut lights);
        let aovs = output_aovs(&automaton, aovs, &light_groups);
        let data_live = data_live(&automaton, &objects, classes.data_light);
        let lights_only_live = lights_only_live(&automaton, &lights);
        Ok(Scene {
            accel,
            surface,
            mesh_lights,
            objects,
            materials,
            light_select,
            first_glow_light: first_glow_light as u32,
            escape_lights: lights::escape_lights(&lights),
            lights,
            camera,
            filter: camera::filter(desc),
            settings,
            camera_class: classes.camera,
            data_light_class: classes.data_light,
            automaton,
            aovs,
            scene_center,
            scene_radius,
            epsilon,
            light_groups,
            lights_only_live,
            data_live,
            variance_aovs: Vec::new(),
            volumes,
            atmosphere,
            camera_media,
            has_media,
            has_presence,
        })
    }
}

fn new_object(name: String, groups: Vec<String>) -> Object {
    Object {
        name,
        groups,
        material: None,
        emission: Vec3A::ZERO,
        light: None,
        holdout: false,
        unlit_by: Vec::new(),
        unshadowing: Vec::new(),
        lobe_classes: Vec::new(),
        data_lobes: Vec::new(),
        glow_class: None,
        glow_light: None,
        interior: None,
        priority: 0,
        null_surface: false,
    }
}

/// The scene's objects, their primitives added to `geometry` (at the returned ranges of
/// the primitive list, one per object).
fn add_objects(
    desc: &SceneDesc,
    material_ids: &HashMap<String, u32>,
    geometry: &mut GeometryBuilder,
) -> Result<(Vec<Object>, Vec<Range<u32>>), SceneError> {
    let mut objects: Vec<Object> = Vec::new();
    let mut ranges = Vec::new();
    let users = geometry::shared_mesh_users(&desc.objects);
    // Objects whose triangles a mesh light samples stay in the scene's own list.
    let mesh_light_objects: Vec<usize> = desc
        .lights
        .iter()
        .filter_map(|l| match l.kind {
            LightKind::Mesh { object } => Some(object),
            _ => None,
        })
        .collect();
    for o in &desc.objects {
        let name = o
            .name
            .clone()
            .unwrap_or_else(|| format!("object{}", objects.len()));
        // An infinite emission is allowed: it is what the `noinfinitecheck` prefix is
        // for (the NaN/Inf filter drops it from every other AOV). NaN is not.
        if let Some(e) = o
            .emission
            .filter(|e| e.iter().any(|v| v.is_nan() || *v < 0.0))
        {
            return Err(o.origin.error(format!(
                "emission is {e:?}: expected non-negative numbers (not NaN)"
            )));
        }
        let id = objects.len() as u32;
        let visibility = (o.visible_camera as u8 * Visibility::CAMERA)
            | (o.visible_indirect as u8 * Visibility::INDIRECT)
            | (o.casts_shadows as u8 * Visibility::SHADOW);
        match &o.shape {
            // A mesh several objects share: stored once, placed as an instance (no
            // primitives of its own in the scene's list).
            ShapeDesc::SharedMesh { parts }
                if users[&geometry::mesh_key(parts)] > 1
                    && !mesh_light_objects.contains(&(id as usize)) =>
            {
                geometry.add_instance(id, parts, &o.transform, visibility, &o.origin)?;
                ranges.push(geometry.len()..geometry.len());
            }
            shape => {
                let shape = geometry::shape_prims(shape, &o.transform, &o.origin)?;
                ranges.push(geometry.add(id, shape, visibility));
            }
        }
        let groups = o.lpegroups.clone().unwrap_or_else(|| vec![name.clone()]);
        // The object's own emission, else its OpenPBR material's.
        let emission = o.emission.map(Vec3A::from).or_else(|| {
            let m = desc.materials.get(&o.material.as_ref()?.name)?;
            materials::emission(m)
        });
        // `material = "null"` (unless the scene defines a material of that name): an
        // index-matched boundary of a medium, with no surface event.
        let null_surface = o
            .material
            .as_ref()
            .is_some_and(|m| m.name == "null" && !material_ids.contains_key("null"));
        let material = if null_surface {
            None
        } else {
            materials::find(desc, material_ids, &o.material)?
        };
        objects.push(Object {
            material,
            emission: emission.unwrap_or(Vec3A::ZERO),
            holdout: o.holdout,
            null_surface,
            ..new_object(name, groups)
        });
    }
    Ok((objects, ranges))
}

/// Where an area light's primitives were added to the scene's primitive list.
type LightPrims = Option<Range<u32>>;

/// The scene's lights; the surface of each area light becomes an object too, its
/// primitives at the returned range of the primitive list.
fn add_lights(
    desc: &SceneDesc,
    material_ids: &HashMap<String, u32>,
    geometry: &mut GeometryBuilder,
    objects: &mut Vec<Object>,
) -> Result<(Vec<Light>, Vec<LightPrims>), SceneError> {
    let mut lights = Vec::new();
    let mut ranges = Vec::new();
    for l in &desc.lights {
        let (shape, surface, color) = lights::light_shape(l)?;
        let light_id = lights.len() as u32;
        let mut range = None;
        let object = surface.map(|sp| {
            let id = objects.len() as u32;
            let camera = if l.camera_visible {
                Visibility::CAMERA
            } else {
                0
            };
            let shadow = if l.casts_shadows {
                Visibility::SHADOW
            } else {
                0
            };
            range = Some(geometry.add(id, sp, camera | Visibility::INDIRECT | shadow));
            let name = l.name.clone().unwrap_or_else(|| format!("light{light_id}"));
            let groups = if l.groups.is_empty() {
                vec![name.clone()]
            } else {
                l.groups.clone()
            };
            objects.push(Object {
                light: Some(light_id),
                ..new_object(name, groups)
            });
            id
        });
        if let Some(id) = object {
            objects[id as usize].material = materials::find(desc, material_ids, &l.material)?;
        }
        let object = match l.kind {
            LightKind::Mesh { object: o } => Some(mesh_light_object(l, o, light_id, objects)?),
            _ => object,
        };
        lights.push(Light {
            groups: l.groups.clone(),
            camera_visible: l.camera_visible,
            object,
            ..Light::new(shape, color)
        });
        ranges.push(range);
    }
    Ok((lights, ranges))
}

/// Makes object `o` the surface of mesh light `light_id`: its emission is the light's.
fn mesh_light_object(
    l: &LightDesc,
    o: usize,
    light_id: u32,
    objects: &mut [Object],
) -> Result<u32, SceneError> {
    let Some(obj) = objects.get_mut(o) else {
        return Err(l.origin.error(format!(
            "mesh light: there is no object {o} (the scene has {})",
            objects.len()
        )));
    };
    if obj.light.is_some() {
        return Err(l.origin.error(format!(
            "object '{}' is already the surface of another light",
            obj.name
        )));
    }
    obj.light = Some(light_id);
    // Its light emits; a glow as well would count the emission twice.
    obj.emission = Vec3A::ZERO;
    Ok(o as u32)
}

/// The output AOVs: one per rule, then the parts of those split per light group.
fn output_aovs(automaton: &Automaton, aovs: &[AovSpec], light_groups: &[String]) -> Vec<Aov> {
    let mut out: Vec<Aov> = automaton
        .rules()
        .iter()
        .zip(aovs)
        .map(|(rule, spec)| Aov {
            name: spec.name.clone(),
            definition: spec.definition.clone(),
            expression: rule.expression.clone(),
            flags: rule.flags,
            split_base: None,
            part_of: None,
        })
        .collect();
    for (k, spec) in aovs.iter().enumerate() {
        if !spec.split_light_groups {
            continue;
        }
        out[k].split_base = Some(out.len() as u32);
        let parts: Vec<Option<&str>> = light_groups
            .iter()
            .map(|g| Some(g.as_str()))
            .chain([None])
            .collect();
        for g in parts {
            let base = &out[k];
            out.push(Aov {
                name: crate::aov::naming::split_name(&spec.name, g),
                definition: crate::aov::naming::split_definition(&spec.definition, g),
                expression: base.expression.clone(),
                flags: base.flags,
                split_base: None,
                part_of: Some(k as u32),
            });
        }
    }
    out
}

/// Per automaton state: can some object's data lobe be accepted from there?
fn data_live(automaton: &Automaton, objects: &[Object], data_light: ClassId) -> Vec<bool> {
    let data_classes: Vec<ClassId> = objects
        .iter()
        .flat_map(|o| o.data_lobes.iter().map(|d| d.1))
        .collect();
    automaton
        .states()
        .map(|s| {
            data_classes.iter().any(|c| {
                !automaton
                    .accepting(automaton.step(automaton.step(s, *c), data_light))
                    .is_empty()
            })
        })
        .collect()
}

/// Per automaton state (a path's state after a scatter event): can some light's event
/// from here be accepted by an `unoccluded` or `shadows` AOV? Only there does the
/// integrator test a BSDF ray against the lights alone (direct.rs, `lights_only`). The
/// standard `albedo`, `depth` and `normal` AOVs carry `unoccluded` but take a light's
/// event only after a data lobe's, which no path continues from: in most renders no state
/// a path scatters into is live.
fn lights_only_live(automaton: &Automaton, lights: &[Light]) -> Vec<bool> {
    let wanted: Vec<bool> = automaton
        .rules()
        .iter()
        .map(|r| {
            r.flags.contains(lpe::Prefix::Unoccluded) || r.flags.contains(lpe::Prefix::Shadows)
        })
        .collect();
    if !wanted.contains(&true) {
        return vec![false; automaton.states().count()];
    }
    // Lights share classes (a group's lights, unnamed ones): each class once.
    let classes: std::collections::HashSet<ClassId> =
        lights.iter().map(|l| l.classes.light).collect();
    automaton
        .states()
        .map(|s| {
            classes.iter().any(|&c| {
                automaton
                    .accepting(automaton.step(s, c))
                    .iter()
                    .any(|r| wanted[r.0 as usize])
            })
        })
        .collect()
}

/// Compiles the AOVs into one automaton whose alphabet is exactly the scene's events.
fn compile_aovs(
    desc: &SceneDesc,
    aovs: &[AovSpec],
    vocabulary: &Vocabulary,
) -> Result<Automaton, SceneError> {
    let mut compiler = lpe::Compiler::new()
        .profile(crate::events::profile())
        .default_alphabet(false);
    for spec in aovs {
        compiler
            .add(crate::aov::resolve_definition(&spec.definition))
            .map_err(|e| {
                let origin = desc
                    .aovs
                    .get(&spec.name)
                    .map_or_else(|| Origin::file(&desc.source), |a| a.origin.clone());
                origin.error(format!(
                    "AOV '{}': {}",
                    spec.name,
                    e.render(&spec.definition).trim_end()
                ))
            })?;
    }
    compiler.vocabulary(vocabulary.events().iter().cloned());
    compiler.compile().map_err(|e| {
        Origin::file(&desc.source).error(format!(
            "the AOV expressions are too complex together: {}",
            e.message
        ))
    })
}

#[cfg(test)]
mod tests {
    use crate::aov::{self, AovSpec};
    use crate::scene::{Scene, Source};

    fn room(aovs: Vec<AovSpec>) -> Scene {
        let desc = Source {
            name: "room.toml".into(),
            text: "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 30\n\
                   [materials.white]\ntype = \"diffuse\"\nalbedo = [0.8, 0.8, 0.8]\n\
                   [[objects]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\
                   material = \"white\"\n\
                   [[lights]]\ntype = \"point\"\nposition = [2, 2, 2]\n\
                   intensity = [10, 10, 10]\n"
                .into(),
            dir: Default::default(),
        }
        .parse()
        .unwrap();
        Scene::build(&desc, &aov::assemble(aovs)).unwrap()
    }

    /// The states a real path is in past the camera and each diffuse bounce: the
    /// standard AOVs' `unoccluded` rules (albedo, depth, normal) take a light's event only
    /// after a data lobe's, so none of them asks for the lights-only test there. An
    /// `unoccluded` light AOV does, after its diffuse event but not at the camera.
    #[test]
    fn lights_only_is_live_only_where_an_unoccluded_light_aov_can_accept() {
        let path_states = |scene: &Scene| {
            let a = &scene.automaton;
            let diffuse = scene.objects[0].lobe_classes[0];
            let camera = a.step(a.start(), scene.camera_class);
            let once = a.step(camera, diffuse);
            let twice = a.step(once, diffuse);
            [camera, once, twice].map(|s| scene.lights_only_live[a.state_index(s)])
        };
        assert_eq!(path_states(&room(aov::standard())), [false; 3]);
        let with = room(vec![AovSpec::new("u", "unoccluded;C<RD>L")]);
        assert_eq!(path_states(&with), [false, true, false]);
    }
}
