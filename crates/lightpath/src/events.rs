//! The one owner of the event vocabulary: which LPE event each (object, lobe) pair, each
//! data lobe, each light and each glowing surface emits. The scene's vocabulary is built
//! once, compiled with the AOVs, and that same list is classified, so every event the
//! integrator steps has a class by construction.

use crate::light::{Light, LightClasses};
use crate::scene::{Material, Object};
use glam::Vec3A;
use lpe::{Automaton, ClassId, Event, EventType, Profile, Scatter};

/// What Lightpath's paths contain: every type but background (`B`).
pub fn profile() -> Profile {
    use EventType::*;
    Profile::new(&[Camera, Reflect, Transmit, Light, Emission, Volume])
}

/// What a user (data) lobe reports (docs/lpe.md#paths-and-events).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataLobe {
    Albedo,
    Position,
    Normal,
    UserColor,
    /// The camera-space depth of the point (Lightpath's own lobe number, `U7`).
    Depth,
}

impl DataLobe {
    /// Its lobe: `U2` albedo, `U3` position, `U4` user colour, `U6` normal (RenderMan's
    /// numbers), `U7` depth.
    pub fn scatter(self) -> Scatter {
        Scatter::user(match self {
            DataLobe::Albedo => 2,
            DataLobe::Position => 3,
            DataLobe::UserColor => 4,
            DataLobe::Normal => 6,
            DataLobe::Depth => 7,
        })
    }
}

/// What in the scene emits an event of the vocabulary.
#[derive(Clone, Copy, Debug)]
enum Use {
    Camera,
    /// `L` with no labels: the unit light data lobes are evaluated under.
    DataLight,
    /// A BSDF lobe of an object (in the BSDF's lobe order).
    Lobe {
        object: u32,
    },
    Data {
        object: u32,
        lobe: DataLobe,
    },
    /// A glowing (non-light) surface, seen as `O`.
    Glow {
        object: u32,
    },
    /// A light reached: `L`.
    Light {
        light: u32,
    },
    /// A light seen without a scatter: `O`.
    LightSeen {
        light: u32,
    },
    /// A scattering vertex in an object's interior: `V`.
    VolumeScatter {
        object: u32,
    },
    /// An object's interior's emission: `O`.
    VolumeGlow {
        object: u32,
    },
    /// The atmosphere's `V` and `O` (no labels).
    AtmosphereScatter,
    AtmosphereGlow,
}

/// Every event a scene can emit, each with what emits it.
pub struct Vocabulary {
    events: Vec<Event>,
    uses: Vec<Use>,
}

/// The classes of the events that are neither an object's nor a light's.
pub struct Classes {
    pub camera: ClassId,
    pub data_light: ClassId,
    /// The atmosphere's `V` and `O` (the camera's class when there is none).
    pub atmosphere_scatter: ClassId,
    pub atmosphere_glow: ClassId,
}

impl Vocabulary {
    /// `atmosphere`: whether the scene has one.
    pub fn of_scene(
        objects: &[Object],
        materials: &[Material],
        lights: &[Light],
        atmosphere: bool,
    ) -> Vocabulary {
        let mut v = Vocabulary {
            events: Vec::new(),
            uses: Vec::new(),
        };
        v.push(Event::camera(), Use::Camera);
        v.push(Event::bare(EventType::Light), Use::DataLight);
        for (id, o) in objects.iter().enumerate() {
            let object = id as u32;
            if let Some(m) = o.material.map(|m| &materials[m as usize]) {
                for t in m.bsdf.lobes() {
                    let ty = if t.transmit {
                        EventType::Transmit
                    } else {
                        EventType::Reflect
                    };
                    v.push(
                        Event::new(ty, Some(t.scatter), o.groups.iter()),
                        Use::Lobe { object },
                    );
                }
                let mut kinds = vec![
                    DataLobe::Albedo,
                    DataLobe::Position,
                    DataLobe::Normal,
                    DataLobe::Depth,
                ];
                if m.user_color.is_some() {
                    kinds.push(DataLobe::UserColor);
                }
                for lobe in kinds {
                    let e = Event::new(EventType::Reflect, Some(lobe.scatter()), o.groups.iter());
                    v.push(e, Use::Data { object, lobe });
                }
            }
            if o.emission != Vec3A::ZERO {
                let e = Event::new(EventType::Emission, None, o.groups.iter());
                v.push(e, Use::Glow { object });
            }
            if o.interior.is_some() {
                let e = Event::new(EventType::Volume, None, o.groups.iter());
                v.push(e, Use::VolumeScatter { object });
                let e = Event::new(EventType::Emission, None, o.groups.iter());
                v.push(e, Use::VolumeGlow { object });
            }
        }
        if atmosphere {
            v.push(Event::bare(EventType::Volume), Use::AtmosphereScatter);
            v.push(Event::bare(EventType::Emission), Use::AtmosphereGlow);
        }
        // A glow's events are its object's `O` (above), not a light's.
        for (id, l) in lights.iter().enumerate().filter(|(_, l)| !l.glow) {
            let light = id as u32;
            v.push(
                Event::new(EventType::Light, None, l.groups.iter()),
                Use::Light { light },
            );
            let e = Event::new(EventType::Emission, None, l.groups.iter());
            v.push(e, Use::LightSeen { light });
        }
        v
    }

    fn push(&mut self, e: Event, u: Use) {
        self.events.push(e);
        self.uses.push(u);
    }

    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// Stores each object's and each light's classes and returns the others;
    /// `automaton` must have been compiled with exactly `events()` as its vocabulary.
    pub fn classify(
        &self,
        automaton: &Automaton,
        objects: &mut [Object],
        lights: &mut [Light],
    ) -> Classes {
        let classes = automaton.vocabulary_classes();
        let mut out = Classes {
            camera: classes[0],
            data_light: classes[1],
            atmosphere_scatter: classes[0],
            atmosphere_glow: classes[0],
        };
        for o in objects.iter_mut() {
            o.lobe_classes.clear();
            o.data_lobes.clear();
            o.glow_class = None;
        }
        for (u, &class) in self.uses.iter().zip(classes) {
            match *u {
                Use::Camera => out.camera = class,
                Use::DataLight => out.data_light = class,
                Use::Lobe { object } => objects[object as usize].lobe_classes.push(class),
                Use::Data { object, lobe } => {
                    objects[object as usize].data_lobes.push((lobe, class))
                }
                Use::Glow { object } => objects[object as usize].glow_class = Some(class),
                Use::Light { light } => lights[light as usize].classes.light = class,
                Use::LightSeen { light } => lights[light as usize].classes.seen = class,
                Use::VolumeScatter { object } => {
                    if let Some(i) = &mut objects[object as usize].interior {
                        i.scatter_class = class;
                    }
                }
                Use::VolumeGlow { object } => {
                    if let Some(i) = &mut objects[object as usize].interior {
                        i.glow_class = class;
                    }
                }
                Use::AtmosphereScatter => out.atmosphere_scatter = class,
                Use::AtmosphereGlow => out.atmosphere_glow = class,
            }
        }
        // A light sample of a glow, like a ray that finds it, is its object's `O`.
        for l in lights.iter_mut().filter(|l| l.glow) {
            let object = &objects[l.object.expect("a glow has its object") as usize];
            let glow = object.glow_class.expect("a glowing object has its O class");
            l.classes = LightClasses {
                light: glow,
                seen: glow,
            };
        }
        // Keep only data lobes some rule can accept: the others would cost two steps per
        // vertex for nothing.
        for o in objects.iter_mut() {
            o.data_lobes.retain(|(_, class)| {
                automaton.states().any(|s| {
                    let after = automaton.step(s, *class);
                    !automaton
                        .accepting(automaton.step(after, out.data_light))
                        .is_empty()
                })
            });
        }
        out
    }
}
