//! USD stages written by the tests themselves (usda text, and a .usdz packed with the
//! `openusd` crate's writer): composition as the crate does it, meshes, instances,
//! UsdPreviewSurface materials, UsdLux lights in the specification's units, render
//! settings and their vars as the AOVs, and errors that name the layer and the prim.

use crate::common::Scratch;
use lightpath::aov;
use lightpath::scene::desc::Origin;
use lightpath::scene::desc::{LightKind, MaterialDesc, MaterialKind, SceneDesc, ShapeDesc};
use lightpath::scene::load::usd::{load_scene, UsdOptions};
use lightpath::{render, RenderOptions, Scene};
use std::f32::consts::PI;
use std::path::Path;

fn write(dir: &Scratch, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn load(path: &Path) -> SceneDesc {
    load_with(path, &UsdOptions::default())
}

fn load_with(path: &Path, options: &UsdOptions) -> SceneDesc {
    load_scene(path, &Origin::file("test"), options).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(path: &Path) -> String {
    match load_scene(path, &Origin::file("test"), &UsdOptions::default()) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => e.to_string(),
    }
}

const SHOT: &str = r#"#usda 1.0
(
    upAxis = "Y"
    metersPerUnit = 1
    renderSettingsPrimPath = "/Render/Settings"
)

def Xform "World"
{
    def Camera "Cam"
    {
        float focalLength = 35
        float horizontalAperture = 36
        float verticalAperture = 24
        double3 xformOp:translate = (0, 1, 6)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def Mesh "Floor" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(-5, 0, 5), (5, 0, 5), (5, 0, -5), (-5, 0, -5)]
        rel material:binding = </World/Looks/Red>
        string primvars:karma:object:lpetag = "floor"
    }
    def Scope "Looks"
    {
        def Material "Red"
        {
            token outputs:surface.connect = </World/Looks/Red/PBR.outputs:surface>
            def Shader "PBR"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor = (0.8, 0.1, 0.1)
                float inputs:roughness = 0.4
                float inputs:metallic = 0.25
                token outputs:surface
            }
        }
    }
    def RectLight "Key"
    {
        float inputs:intensity = 20
        float inputs:width = 2
        float inputs:height = 0.5
        bool inputs:normalize = true
        string karma:light:lpetag = "key"
        double3 xformOp:translate = (0, 4, 0)
        float3 xformOp:rotateXYZ = (-90, 0, 0)
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
    }
    def SphereLight "Fill"
    {
        float inputs:intensity = 8
        float inputs:radius = 0.25
        string ri:light:lightGroup = "fill"
    }
}

def Scope "Render"
{
    def RenderSettings "Settings"
    {
        rel products = </Render/Product>
        uniform int2 resolution = (160, 120)
        rel camera = </World/Cam>
    }
    def RenderProduct "Product"
    {
        rel orderedVars = [</Render/Vars/diffuseKey>, </Render/Vars/N>, </Render/Vars/Ci>, </Render/Vars/spec>]
        token productName = "shot_out.exr"
        uniform int2 resolution = (160, 120)
        rel camera = </World/Cam>
    }
    def Scope "Vars"
    {
        def RenderVar "diffuseKey"
        {
            uniform string sourceName = "C<RD>[<L.'key'>O]"
            uniform token sourceType = "lpe"
        }
        def RenderVar "N"
        {
            uniform string sourceName = "normal"
            uniform token sourceType = "raw"
        }
        def RenderVar "Ci"
        {
            uniform string sourceName = "Ci"
            uniform token sourceType = "raw"
        }
        def RenderVar "spec"
        {
            uniform string sourceName = "lpe:C<RS>.*L"
            uniform token sourceType = "lpe"
            string driver:parameters:aov:name = "specular"
        }
    }
}
"#;

#[test]
fn render_settings_give_film_camera_output_and_exactly_the_vars() {
    let dir = Scratch::new("usd-settings");
    let desc = load(&write(&dir, "shot.usda", SHOT));
    assert_eq!(desc.render.resolution, [160, 120]);
    assert_eq!(desc.standard_aovs, Some(false));
    assert_eq!(desc.output.as_deref(), Some(Path::new("shot_out.exr")));
    let aovs: Vec<(&str, &str)> = desc
        .aovs
        .iter()
        .map(|(n, a)| (n.as_str(), a.definition.as_str()))
        .collect();
    // Ci is the beauty; the named var keeps its name, `lpe:` before an expression goes.
    let normal = aov::AovSpec::parse("normal").unwrap().definition;
    assert_eq!(
        aovs,
        vec![
            ("N", normal.as_str()),
            ("diffuseKey", "C<RD>[<L.'key'>O]"),
            ("specular", "C<RS>.*L"),
        ]
    );
    // The settings' camera; 3:2 apertures on a 4:3 film keep the horizontal aperture.
    let cam = desc.camera.as_ref().unwrap();
    assert_eq!(cam.position, [0.0, 1.0, 6.0]);
    let fov = 2.0 * (18.0f32 / 35.0).atan().to_degrees();
    assert!((cam.fov - fov).abs() < 1e-3, "{} vs {fov}", cam.fov);
    // Tags: Karma's on the object and the light, RenderMan's on a light.
    let floor = &desc.objects[0];
    assert_eq!(
        floor.lpegroups.as_deref().unwrap(),
        ["floor", "Floor", "World"]
    );
    let groups: Vec<&str> = desc.lights.iter().map(|l| l.groups[0].as_str()).collect();
    assert_eq!(groups, ["key", "fill"]);
    // The bound UsdPreviewSurface, on OpenPBR.
    let m = &desc.materials[&floor.material.as_ref().unwrap().name];
    let MaterialKind::OpenPbr(p) = &m.kind else {
        panic!("{:?}", m.kind)
    };
    assert_eq!(p.base_color.to_array(), [0.8, 0.1, 0.1]);
    assert_eq!((p.specular_roughness, p.base_metalness), (0.4, 0.25));
    // A normalized rect light: radiance is intensity over its area.
    let key = &desc.lights[0];
    assert!(matches!(key.kind, LightKind::Rectangle));
    assert!((key.strength - 20.0 / (2.0 * 0.5)).abs() < 1e-4);
    // It faces down: its +z (the side Lightpath's rectangle emits on) is world −Y.
    let n = key.transform.transform_vector3a(glam::Vec3A::Z).normalize();
    assert!((n - glam::Vec3A::NEG_Y).length() < 1e-5, "{n}");
}

#[test]
fn render_vars_are_the_aovs_of_the_render() {
    let dir = Scratch::new("usd-job");
    let scene = write(&dir, "shot.usda", SHOT);
    let out = dir.join("out.exr");
    let mut job = lightpath::job::RenderJob::new(scene.to_string_lossy());
    job.output = Some(out.clone());
    job.overrides.spp = Some(1);
    let prepared = job.clone().prepare().unwrap();
    let names: Vec<&str> = prepared
        .scene
        .aovs
        .iter()
        .map(|a| a.name.as_str())
        .collect();
    assert_eq!(names, ["beauty", "N", "diffuseKey", "specular"]);
    // --aovs standard adds the standard set.
    job.aovs.standard_asked = true;
    let prepared = job.prepare().unwrap();
    assert!(prepared.scene.aovs.iter().any(|a| a.name == "diffuse"));
}

#[test]
fn composition_sublayers_references_payloads_and_variants() {
    let dir = Scratch::new("usd-compose");
    write(
        &dir,
        "asset.usda",
        r#"#usda 1.0
(
    defaultPrim = "Asset"
)
def Xform "Asset" (
    variants = { string size = "big" }
    prepend variantSets = "size"
)
{
    variantSet "size" = {
        "big" {
            def Sphere "Ball" { double radius = 2 }
        }
        "small" {
            def Sphere "Ball" { double radius = 0.5 }
        }
    }
}
"#,
    );
    write(
        &dir,
        "payload.usda",
        r#"#usda 1.0
(
    defaultPrim = "P"
)
def Xform "P"
{
    def Cube "Box" { double size = 4 }
}
"#,
    );
    write(
        &dir,
        "lights.usda",
        r#"#usda 1.0
def DistantLight "Sun" { float inputs:intensity = 3 bool inputs:normalize = true }
"#,
    );
    let root = write(
        &dir,
        "root.usda",
        r#"#usda 1.0
(
    subLayers = [@lights.usda@]
    metersPerUnit = 1
)
def Xform "A" (
    prepend references = @asset.usda@
)
{
    double3 xformOp:translate = (1, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Xform "B" (
    prepend references = @asset.usda@
    variants = { string size = "small" }
)
{
}
def Xform "C" (
    prepend payload = @payload.usda@
)
{
}
"#,
    );
    let desc = load(&root);
    let radius = |name: &str| {
        desc.objects
            .iter()
            .find(|o| o.lpegroups.as_ref().unwrap().contains(&name.to_string()))
            .map(|o| match o.shape {
                ShapeDesc::Sphere { radius, .. } => (radius, o.transform.translation.x),
                _ => panic!(),
            })
            .unwrap()
    };
    assert_eq!(radius("A"), (2.0, 1.0));
    assert_eq!(radius("B"), (0.5, 0.0));
    let cube = desc
        .objects
        .iter()
        .find(|o| o.shape_name == "Cube")
        .unwrap();
    assert!((cube.transform.matrix3.x_axis.x - 2.0).abs() < 1e-6);
    assert_eq!(desc.lights.len(), 1);
    assert!(matches!(desc.lights[0].kind, LightKind::Distant { .. }));
    assert_eq!(desc.lights[0].strength, 3.0);
    // And it renders as composed: the command line's default camera frames the two
    // balls and the box, lit by the sublayer's sun.
    let out = dir.join("root.exr");
    let mut job = lightpath::job::RenderJob::new(root.to_string_lossy());
    job.output = Some(out.clone());
    job.overrides.spp = Some(1);
    job.overrides.resolution = Some([24, 16]);
    job.prepare()
        .unwrap()
        .run(&lightpath::progress::Silent)
        .unwrap();
    let exr = lightpath::output::read_exr(&out).unwrap();
    let lit = exr
        .channels
        .iter()
        .find(|(name, _)| name == "R")
        .map(|(_, data)| data.iter().filter(|v| **v > 0.0).count())
        .unwrap();
    assert!(lit > 0, "nothing of the composed stage is lit");
}

#[test]
fn meshes_polygons_subsets_primvars_purpose_visibility_and_up_axis() {
    let dir = Scratch::new("usd-mesh");
    let p = write(
        &dir,
        "mesh.usda",
        r#"#usda 1.0
(
    upAxis = "Z"
    metersPerUnit = 0.01
)
def Mesh "M"
{
    int[] faceVertexCounts = [4, 3, 3]
    int[] faceVertexIndices = [0, 1, 2, 3, 0, 2, 4, 1, 2, 4]
    int[] holeIndices = [2]
    point3f[] points = [(0, 0, 0), (100, 0, 0), (100, 100, 0), (0, 100, 0), (50, 50, 100)]
    texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (interpolation = "faceVarying")
    int[] primvars:st:indices = [0, 1, 2, 3, 0, 2, 3, 0, 1, 2]
    def GeomSubset "Top" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {
        uniform token elementType = "face"
        uniform token familyName = "materialBind"
        int[] indices = [1]
        rel material:binding = </Looks/Blue>
    }
}
def Sphere "Proxy" { uniform token purpose = "proxy" }
def Sphere "Hidden" { token visibility = "invisible" }
def Scope "Looks"
{
    def Material "Blue"
    {
        token outputs:surface.connect = </Looks/Blue/S.outputs:surface>
        def Shader "S"
        {
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor = (0, 0, 1)
            token outputs:surface
        }
    }
}
"#,
    );
    let desc = load(&p);
    // The hole is skipped; the quad and the subset's triangle are two parts.
    assert_eq!(
        desc.objects.len(),
        2,
        "{:?}",
        desc.objects.iter().map(|o| &o.name).collect::<Vec<_>>()
    );
    let parts: Vec<&lightpath::scene::desc::MeshData> = desc
        .objects
        .iter()
        .map(|o| &o.shape.mesh_parts().unwrap()[0])
        .collect();
    assert_eq!(parts[0].indices.len(), 2);
    assert_eq!(parts[1].indices.len(), 1);
    assert_eq!(
        desc.objects[1].material.as_ref().unwrap().name,
        "/Looks/Blue"
    );
    // faceVarying st: a vertex per corner, t flipped to Lightpath's top-left origin.
    assert_eq!(parts[0].positions.len(), 4);
    assert_eq!(parts[0].uvs.as_ref().unwrap()[0], [0.0, 1.0]);
    // Z up and centimetres: (100, 100, 0) cm is (1, 0, -1) m in Lightpath's Y-up world.
    let world = |p: [f32; 3]| desc.objects[0].transform.transform_point3a(p.into());
    assert!((world([100.0, 100.0, 0.0]) - glam::Vec3A::new(1.0, 0.0, -1.0)).length() < 1e-5);
}

#[test]
fn instances_share_their_prototype_and_point_instancers_place_copies() {
    let dir = Scratch::new("usd-instances");
    let p = write(
        &dir,
        "inst.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Xform "Proto"
{
    def Mesh "Tri"
    {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    }
}
over "Src"
{
    def Mesh "Tri"
    {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    }
}
def Xform "I1" (instanceable = true
    prepend references = </Src>)
{
    double3 xformOp:translate = (5, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Xform "I2" (instanceable = true
    prepend references = </Src>)
{
    double3 xformOp:translate = (-5, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def PointInstancer "PI"
{
    rel prototypes = </PI/Protos/Ball>
    int[] protoIndices = [0, 0, 0]
    point3f[] positions = [(0, 0, 10), (0, 0, 20), (0, 0, 30)]
    int64[] invisibleIds = [1]
    def Scope "Protos"
    {
        def Sphere "Ball" { double radius = 0.5 }
    }
}
"#,
    );
    let desc = load(&p);
    let tris: Vec<_> = desc
        .objects
        .iter()
        .filter(|o| o.shape_name == "Mesh")
        .collect();
    assert_eq!(tris.len(), 3, "Proto's own mesh and the two instances");
    let shared = |o: &lightpath::scene::desc::ObjectDesc| match &o.shape {
        ShapeDesc::SharedMesh { parts } => parts.clone(),
        _ => panic!(),
    };
    assert!(std::sync::Arc::ptr_eq(&shared(tris[1]), &shared(tris[2])));
    let xs: Vec<f32> = tris[1..]
        .iter()
        .map(|o| o.transform.translation.x)
        .collect();
    assert_eq!(xs, [5.0, -5.0]);
    let balls: Vec<f32> = desc
        .objects
        .iter()
        .filter(|o| o.shape_name == "Sphere")
        .map(|o| o.transform.translation.z)
        .collect();
    assert_eq!(
        balls,
        [10.0, 30.0],
        "id 1 is invisible, prototypes are not drawn themselves"
    );
}

#[test]
fn lights_in_the_usdlux_specifications_units() {
    let dir = Scratch::new("usd-lights");
    let p = write(
        &dir,
        "lights.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def SphereLight "Bulb" { float inputs:intensity = 10 float inputs:radius = 0.5 bool treatAsPoint = true }
def SphereLight "BulbN" { float inputs:intensity = 10 float inputs:radius = 0.5 bool inputs:treatAsPoint = true bool inputs:normalize = true }
def SphereLight "Ball" { float inputs:intensity = 10 float inputs:exposure = 1 float inputs:radius = 0.5 bool inputs:normalize = true }
def DistantLight "Sun" { float inputs:intensity = 1000 float inputs:angle = 1 }
def DiskLight "Disk" { float inputs:intensity = 2 float inputs:radius = 2 bool inputs:normalize = true
    bool inputs:enableColorTemperature = true float inputs:colorTemperature = 6500 }
def CylinderLight "Tube" { float inputs:intensity = 3 float inputs:length = 2 float inputs:radius = 0.1 bool inputs:normalize = true
    bool inputs:enableColorTemperature = true float inputs:colorTemperature = 3000 }
def SphereLight "Spot" (prepend apiSchemas = ["ShapingAPI"])
{
    float inputs:intensity = 4 float inputs:radius = 0.1 bool inputs:treatAsPoint = true
    float inputs:shaping:cone:angle = 30 float inputs:shaping:cone:softness = 0
}
def DomeLight "Sky" { float inputs:intensity = 0.5 }
"#,
    );
    let desc = load(&p);
    let by = |n: &str| {
        desc.lights
            .iter()
            .find(|l| l.name.as_deref() == Some(n))
            .unwrap()
    };
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * b.abs().max(1.0);
    // A point of the sphere's power: L·π·r²; normalized, L/4.
    assert!(matches!(by("Bulb").kind, LightKind::Point { .. }));
    assert!(close(by("Bulb").strength, 10.0 * PI * 0.25));
    assert!(close(by("BulbN").strength, 10.0 / 4.0));
    // exposure 1 doubles; normalize divides by the sphere's area.
    assert!(close(by("Ball").strength, 20.0 / (4.0 * PI * 0.25)));
    // An unnormalized sun: radiance over a disk of diameter 1°.
    assert!(close(
        by("Sun").strength,
        1000.0 * PI * (0.5f32.to_radians()).sin().powi(2)
    ));
    assert!(close(by("Disk").strength, 2.0 / (PI * 4.0)));
    // 6500 K is white; 3000 K is warm, of luminance 1.
    for c in by("Disk").color {
        assert!((c - 1.0).abs() < 1e-4, "{:?}", by("Disk").color);
    }
    let warm = by("Tube").color;
    assert!(warm[0] > warm[1] && warm[1] > warm[2], "{warm:?}");
    let y = 0.2126 * warm[0] + 0.7152 * warm[1] + 0.0722 * warm[2];
    assert!((y - 1.0).abs() < 1e-4);
    assert!(close(by("Tube").strength, 3.0 / (2.0 * PI * 0.1 * 2.0)));
    match by("Spot").kind {
        LightKind::Spot {
            cone_angle,
            cone_softness,
            direction,
            ..
        } => {
            assert!(close(cone_angle, 60.0));
            assert!(cone_softness.abs() < 1e-3);
            assert_eq!(direction, [0.0, 0.0, -1.0]);
        }
        ref k => panic!("{k:?}"),
    }
    assert!(matches!(by("Sky").kind, LightKind::Dome { map: None, .. }));
}

#[test]
fn a_normalized_distant_light_gives_its_intensity_as_irradiance() {
    // A grey (0.5) Lambertian square facing a normalized distant light of intensity π:
    // radiance 0.5 · π / π = 0.5 everywhere the camera sees it (direct light only).
    let dir = Scratch::new("usd-irradiance");
    let p = write(
        &dir,
        "sun.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Camera "Cam"
{
    float focalLength = 50
    float horizontalAperture = 10
    float verticalAperture = 10
    double3 xformOp:translate = (0, 0, 10)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Mesh "Card"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)]
    color3f[] primvars:displayColor = [(0.5, 0.5, 0.5)]
}
def DistantLight "Sun"
{
    float inputs:intensity = 3.14159265
    bool inputs:normalize = true
}
"#,
    );
    let mut desc = load(&p);
    desc.render.resolution = [16, 16];
    desc.render.spp = 4;
    desc.render.max_depth = 2;
    let scene = Scene::build(&desc, &aov::assemble(Vec::new())).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp: 4,
            first_sample: 0,
        },
    );
    // A delta light on a Lambertian surface: every sample is the same, up to float
    // rounding.
    for y in 0..film.height {
        for x in 0..film.width {
            let v = film.pixel(0, x, y);
            assert!((v.x - 0.5).abs() < 1e-3, "pixel {x},{y}: {v}");
        }
    }
}

#[test]
fn a_sun_blender_wrote_is_read_as_blenders_sun_strength() {
    // Blender's exporter writes a sun of strength 1 W/m² as a normalized DistantLight of
    // intensity 0.25 (and reads it back as 4 × 0.25); a TD's layer that overrides the
    // intensity is read by the specification (illuminance = intensity).
    let dir = Scratch::new("usd-blender-sun");
    write(
        &dir,
        "export.usda",
        r#"#usda 1.0
(
    doc = "Blender v5.0.1"
    metersPerUnit = 1
    upAxis = "Z"
)
def Xform "root"
{
    def DistantLight "sun"
    {
        float inputs:intensity = 0.25
        bool inputs:normalize = 1
        float inputs:angle = 0.263
    }
    def DistantLight "moon"
    {
        float inputs:intensity = 0.25
        bool inputs:normalize = 1
    }
}
"#,
    );
    let p = write(
        &dir,
        "td.usda",
        r#"#usda 1.0
(
    subLayers = [@export.usda@]
    metersPerUnit = 1
    upAxis = "Z"
)
over "root"
{
    over "moon"
    {
        float inputs:intensity = 0.5
    }
}
"#,
    );
    let desc = load(&p);
    let by = |n: &str| {
        desc.lights
            .iter()
            .find(|l| l.name.as_deref() == Some(n))
            .unwrap()
    };
    assert_eq!(by("sun").strength, 1.0);
    assert_eq!(by("moon").strength, 0.5);
}

#[test]
fn usd_lights_do_not_block_other_lights() {
    // A rect light between a normalized sun and a card: UsdLux lights are not occluders,
    // so the card gets the sun's full irradiance (radiance 0.5 · π / π with albedo 0.5).
    let dir = Scratch::new("usd-light-shadow");
    let p = write(
        &dir,
        "blocker.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Camera "Cam"
{
    float focalLength = 50
    float horizontalAperture = 10
    float verticalAperture = 10
    double3 xformOp:translate = (0, 0, 10)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Mesh "Card"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)]
    color3f[] primvars:displayColor = [(0.5, 0.5, 0.5)]
}
def DistantLight "Sun"
{
    float inputs:intensity = 3.14159265
    bool inputs:normalize = true
}
def RectLight "Panel"
{
    float inputs:intensity = 0.0001
    float inputs:width = 20
    float inputs:height = 20
    bool karma:light:renderlightgeo = false
    double3 xformOp:translate = (0, 0, 5)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
"#,
    );
    let mut desc = load(&p);
    assert!(desc.lights.iter().all(|l| !l.casts_shadows));
    desc.render.resolution = [8, 8];
    desc.render.spp = 2;
    desc.render.max_depth = 2;
    let scene = Scene::build(&desc, &aov::assemble(Vec::new())).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp: 2,
            first_sample: 0,
        },
    );
    // Delta light, Lambertian card, a black panel seen by neither camera nor shadow rays:
    // every sample is the same up to float rounding.
    for y in 0..film.height {
        for x in 0..film.width {
            let v = film.pixel(0, x, y);
            assert!((v.x - 0.5).abs() < 1e-3, "pixel {x},{y}: {v}");
        }
    }
}

#[test]
fn time_samples_are_read_at_the_frame() {
    let dir = Scratch::new("usd-time");
    let p = write(
        &dir,
        "anim.usda",
        r#"#usda 1.0
(
    startTimeCode = 1
    endTimeCode = 10
    metersPerUnit = 1
)
def Sphere "Ball"
{
    double3 xformOp:translate.timeSamples = { 1: (0, 0, 0), 10: (9, 0, 0) }
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
"#,
    );
    let x = |frame| {
        let d = load_with(
            &p,
            &UsdOptions {
                frame,
                ..UsdOptions::default()
            },
        );
        d.objects[0].transform.translation.x
    };
    assert_eq!(x(None), 0.0, "the start time code");
    assert_eq!(x(Some(10.0)), 9.0);
    assert!((x(Some(4.0)) - 3.0).abs() < 1e-5, "linear interpolation");
}

#[test]
fn a_usdz_with_a_texture_renders_as_packed() {
    let dir = Scratch::new("usd-usdz");
    let mut png = Vec::new();
    image::RgbImage::from_pixel(2, 2, image::Rgb([255, 0, 0]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let layer = r#"#usda 1.0
(
    metersPerUnit = 1
)
def Mesh "Card" (prepend apiSchemas = ["MaterialBindingAPI"])
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (interpolation = "vertex")
    rel material:binding = </M>
}
def Material "M"
{
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader "S"
    {
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>
        token outputs:surface
    }
    def Shader "T"
    {
        uniform token info:id = "UsdUVTexture"
        asset inputs:file = @textures/red.png@
        token inputs:wrapS = "clamp"
        float3 outputs:rgb
    }
}
"#;
    let path = dir.join("card.usdz");
    let mut w = openusd::usdz::ArchiveWriter::create(&path).unwrap();
    w.add_layer("card.usda", layer.as_bytes()).unwrap();
    w.add_layer("textures/red.png", &png).unwrap();
    w.finish().unwrap();
    let desc = load(&path);
    let m = &desc.materials[&desc.objects[0].material.as_ref().unwrap().name];
    let t = m
        .textures
        .base_color
        .as_ref()
        .expect("the base colour texture");
    assert!(
        matches!(&t.image, lightpath::scene::desc::ImageSource::Bytes { bytes, .. } if bytes[..] == png[..]),
        "{}",
        t.image
    );
    assert_eq!(t.wrap[0], lightpath::material::texture::Wrap::Clamp);
    // And the scene builds (the image decodes).
    Scene::build(&desc, &aov::assemble(Vec::new())).unwrap();
}

#[test]
fn errors_name_the_layer_and_the_prim_and_never_panic() {
    let dir = Scratch::new("usd-errors");
    let bad = write(
        &dir,
        "bad.usda",
        "#usda 1.0\ndef Xform \"A\" {\n  double3 xformOp:translate = (1, 2\n}\n",
    );
    let e = load_err(&bad);
    assert!(e.contains("bad.usda"), "{e}");
    let range = write(
        &dir,
        "range.usda",
        r#"#usda 1.0
def Xform "W" {
    def Mesh "M"
    {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 7]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    }
}
"#,
    );
    let e = load_err(&range);
    assert!(
        e.contains("range.usda") && e.contains("/W/M") && e.contains('7'),
        "{e}"
    );
    let tex = write(
        &dir,
        "tex.usda",
        r#"#usda 1.0
def Mesh "M" (prepend apiSchemas = ["MaterialBindingAPI"])
{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    rel material:binding = </Mat>
}
def Material "Mat"
{
    token outputs:surface.connect = </Mat/S.outputs:surface>
    def Shader "S"
    {
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor.connect = </Mat/T.outputs:rgb>
        token outputs:surface
    }
    def Shader "T"
    {
        uniform token info:id = "UsdUVTexture"
        asset inputs:file = @missing.png@
        float3 outputs:rgb
    }
}
"#,
    );
    let e = load_err(&tex);
    assert!(e.contains("/Mat/T") && e.contains("missing.png"), "{e}");
    let mtlx = write(
        &dir,
        "mtlx.usda",
        r#"#usda 1.0
def Mesh "M" (prepend apiSchemas = ["MaterialBindingAPI"])
{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    color3f[] primvars:displayColor = [(0.1, 0.2, 0.3)]
    rel material:binding = </Mat>
}
def Material "Mat"
{
    token outputs:mtlx:surface.connect = </Mat/S.outputs:out>
    def Shader "S"
    {
        uniform token info:id = "ND_standard_surface_surfaceshader"
        token outputs:out
    }
}
"#,
    );
    let desc = load(&mtlx);
    assert_eq!(
        desc.warnings.iter().filter(|w| w.contains("/Mat")).count(),
        1,
        "{:?}",
        desc.warnings
    );
    let m = &desc.materials[&desc.objects[0].material.as_ref().unwrap().name];
    let MaterialKind::OpenPbr(p) = &m.kind else {
        panic!()
    };
    assert_eq!(p.base_color.to_array(), [0.1, 0.2, 0.3]);
    let e = load_err(&dir.join("nothing.usda"));
    assert!(e.contains("nothing.usda"), "{e}");
}

/// The material of a stage with one sphere bound to a UsdPreviewSurface of `inputs`.
fn preview_surface(dir: &Scratch, name: &str, inputs: &str) -> MaterialDesc {
    let stage = format!(
        r#"#usda 1.0
def Sphere "Ball"
{{
    rel material:binding = </Mat>
}}
def Material "Mat"
{{
    token outputs:surface.connect = </Mat/S.outputs:surface>
    def Shader "S"
    {{
        uniform token info:id = "UsdPreviewSurface"
        {inputs}
        token outputs:surface
    }}
}}
"#
    );
    let desc = load(&write(dir, name, &stage));
    desc.materials[&desc.objects[0].material.as_ref().unwrap().name].clone()
}

fn openpbr_of(m: &MaterialDesc) -> lightpath::material::openpbr::OpenPbr {
    match &m.kind {
        MaterialKind::OpenPbr(p) => **p,
        other => panic!("{other:?}"),
    }
}

/// UsdPreviewSurface's specular workflow: `specularColor` is the reflectance at normal
/// incidence with white at grazing, so it becomes an F0-only tint over the index whose F0
/// is its brightest channel; black turns the dielectric's reflection off.
#[test]
fn the_specular_workflow_gives_specular_color_as_f0() {
    let dir = Scratch::new("usd-specular-workflow");
    let material = |name: &str, color: &str| {
        let inputs = format!(
            "int inputs:useSpecularWorkflow = 1\n        color3f inputs:specularColor = {color}\n        \
             float inputs:metallic = 1\n        float inputs:ior = 1.33"
        );
        openpbr_of(&preview_surface(&dir, name, &inputs))
    };
    let p = material("tinted.usda", "(0.08, 0.04, 0.02)");
    assert!(p.specular_color_f0_only);
    assert_eq!(p.base_metalness, 0.0, "the workflow ignores metallic");
    let f0 = ((p.specular_ior - 1.0) / (p.specular_ior + 1.0)).powi(2);
    assert!(
        (f0 - 0.08).abs() < 1e-6,
        "ior {} gives F0 {f0}",
        p.specular_ior
    );
    let tint = p.specular_color * f0;
    assert!(
        (tint - glam::Vec3A::new(0.08, 0.04, 0.02))
            .abs()
            .max_element()
            < 1e-6
    );
    let black = material("black.usda", "(0, 0, 0)");
    assert_eq!(black.specular_weight, 0.0);
}

/// UsdPreviewSurface's opacity is coverage: presence (as Cycles' USD import makes it the
/// Principled alpha), a cut-out with `opacityThreshold`; never a glass.
#[test]
fn preview_surface_opacity_is_presence() {
    let dir = Scratch::new("usd-opacity");
    let veil = preview_surface(&dir, "veil.usda", "float inputs:opacity = 0.3");
    let p = openpbr_of(&veil);
    assert_eq!((p.geometry_opacity, p.transmission_weight), (0.3, 0.0));
    assert!(!p.geometry_thin_walled);
    assert_eq!(veil.textures.opacity_cutoff, None);
    let leaf = preview_surface(
        &dir,
        "leaf.usda",
        "float inputs:opacity = 0.8\n        float inputs:opacityThreshold = 0.5",
    );
    assert_eq!(openpbr_of(&leaf).geometry_opacity, 0.8);
    assert_eq!(leaf.textures.opacity_cutoff, Some(0.5));
}

/// A stage whose RenderVars redefine standard names, rendered with `--aovs standard`,
/// light groups and bounces: its header declares only the partitions that hold.
fn partitions_of(
    dir: &Scratch,
    vars: &str,
    names: &[&str],
) -> Vec<(String, lightpath::aov::naming::PartitionKind)> {
    use lightpath::aov::naming;
    let ordered: Vec<String> = names.iter().map(|n| format!("</Render/{n}>")).collect();
    let text = format!(
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Xform "World"
{{
    def Sphere "Ball" {{ double radius = 1 }}
    def Cube "Floor"
    {{
        double size = 1
        double3 xformOp:translate = (0, -1.5, 0)
        float3 xformOp:scale = (8, 1, 8)
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:scale"]
    }}
    def SphereLight "Bulb"
    {{
        float inputs:intensity = 20
        float inputs:radius = 0.3
        string karma:light:lpetag = "key"
        double3 xformOp:translate = (2, 3, 3)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }}
    def DistantLight "Sun" {{ float inputs:intensity = 2 bool inputs:normalize = true }}
    def Camera "Cam"
    {{
        double3 xformOp:translate = (0, 0, 6)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }}
}}
def Scope "Render"
{{
    def RenderSettings "Settings"
    {{
        rel products = </Render/Out>
        uniform int2 resolution = (12, 9)
    }}
    def RenderProduct "Out"
    {{
        rel orderedVars = [{}]
    }}
    {vars}
}}
"#,
        ordered.join(", ")
    );
    let scene = write(dir, "parts.usda", &text);
    let out = dir.join("parts.exr");
    let mut job = lightpath::job::RenderJob::new(scene.to_string_lossy());
    job.output = Some(out.clone());
    job.overrides.spp = Some(2);
    job.aovs.standard_asked = true;
    job.aovs.light_groups = true;
    job.aovs.bounces = Some(1);
    job.prepare()
        .unwrap()
        .run(&lightpath::progress::Silent)
        .unwrap();
    let exr = lightpath::output::read_exr(&out).unwrap();
    let checks = lightpath::post::check_partitions(&exr);
    for c in &checks {
        // Every declared partition sums to its whole (float rounding only).
        assert!(
            c.max_relative_error <= 1e-4,
            "{} = {:?}: {}",
            c.whole,
            c.parts,
            c.max_relative_error
        );
    }
    let mut kinds: Vec<(String, naming::PartitionKind)> =
        naming::parts_from_attributes(&exr.attributes)
            .into_iter()
            .map(|p| (p.whole, p.kind))
            .collect();
    kinds.sort();
    kinds.dedup();
    kinds
}

#[test]
fn header_declares_only_the_partitions_that_hold_when_vars_redefine_standard_names() {
    use lightpath::aov::naming::PartitionKind::{Bounces, LightGroups, Standard};
    let dir = Scratch::new("usd-partitions");
    let var = |name: &str, ty: &str, source: &str| {
        format!(
            "def RenderVar \"{name}\" {{ uniform string sourceName = \"{source}\" uniform token sourceType = \"{ty}\" }}\n"
        )
    };
    let b = || ("beauty".to_string(), Bounces);
    let l = || ("beauty".to_string(), LightGroups);
    let s = || ("beauty".to_string(), Standard);
    // Standard names with the standard meaning: every partition holds and is declared.
    let vars = var("emission", "raw", "emission") + &var("diffuse", "lpe", "lpe:diffuse");
    assert_eq!(
        partitions_of(&dir, &vars, &["emission", "diffuse"]),
        [s(), b(), l()]
    );
    // A member of the standard partition redefined (direct diffuse from the key only):
    // the standard partition no longer sums and is not declared; the others are.
    let vars = var("directDiffuse", "lpe", "C<RD>[<L.'key'>O]");
    assert_eq!(partitions_of(&dir, &vars, &["directDiffuse"]), [b(), l()]);
    // The beauty itself redefined: neither the standard set nor the bounces sum to it;
    // its light-group split (of the user's beauty) still does.
    let vars = var("beauty", "lpe", "C<RD>L");
    assert_eq!(partitions_of(&dir, &vars, &["beauty"]), [l()]);
}

#[test]
fn shaping_narrows_rect_and_disk_lights() {
    use lightpath::light::triangles::Shaping;
    // The schema's formulas: a hard cone at softness 0, a smoothstep in the angle over
    // the last `softness` share of the cone, |cos θ|^focus.
    let hard = Shaping {
        cutoff: 30f32.to_radians(),
        start: 30f32.to_radians(),
        focus: 0.0,
        tint: glam::Vec3A::ZERO,
    };
    assert_eq!(hard.factor(1.0).x, 1.0);
    assert_eq!(hard.factor(29f32.to_radians().cos()).x, 1.0);
    assert_eq!(hard.factor(31f32.to_radians().cos()).x, 0.0);
    let soft = Shaping {
        cutoff: 40f32.to_radians(),
        start: 20f32.to_radians(),
        focus: 2.0,
        tint: glam::Vec3A::ZERO,
    };
    let c = 30f32.to_radians().cos();
    assert!(
        (soft.factor(c).x - 0.5 * c * c).abs() < 1e-5,
        "{}",
        soft.factor(c)
    );

    let dir = Scratch::new("usd-shaping");
    let p = write(
        &dir,
        "shaped.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Camera "Cam"
{
    float focalLength = 10
    float horizontalAperture = 20
    float verticalAperture = 20
    double3 xformOp:translate = (0, 0, 10)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Mesh "Card"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0)]
    color3f[] primvars:displayColor = [(0.5, 0.5, 0.5)]
}
def RectLight "Panel" (
    prepend apiSchemas = ["ShapingAPI"]
)
{
    float inputs:intensity = 50
    float inputs:width = 1
    float inputs:height = 1
    float inputs:shaping:cone:angle = 30
    float inputs:shaping:focus = 1
    bool karma:light:renderlightgeo = false
    double3 xformOp:translate = (0, 0, 1)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def DiskLight "Disk" (
    prepend apiSchemas = ["ShapingAPI"]
)
{
    float inputs:intensity = 1
    float inputs:shaping:cone:angle = 45
    float inputs:shaping:cone:softness = 0.5
    double3 xformOp:translate = (0, 0, -5)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
"#,
    );
    let mut desc = load(&p);
    let shaping = |n: &str| {
        desc.lights
            .iter()
            .find(|l| l.name.as_deref() == Some(n))
            .unwrap()
            .shaping
    };
    let rect = shaping("Panel").unwrap();
    assert_eq!(
        (rect.cone_angle, rect.cone_softness, rect.focus),
        (30.0, 0.0, 1.0)
    );
    let disk = shaping("Disk").unwrap();
    assert_eq!(
        (disk.cone_angle, disk.cone_softness, disk.focus),
        (45.0, 0.5, 0.0)
    );
    assert!(
        desc.warnings.iter().all(|w| !w.contains("ShapingAPI")),
        "{:?}",
        desc.warnings
    );
    // Direct light only, the card seen from above: under the panel it is lit; a point of
    // the card 2 m aside sees every point of the panel more than 50° off its normal, past
    // the 30° cone, so it gets nothing (it would without the cone).
    desc.render.resolution = [21, 21];
    desc.render.spp = 16;
    desc.render.max_depth = 2;
    let scene = Scene::build(&desc, &aov::assemble(Vec::new())).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp: 16,
            first_sample: 0,
        },
    );
    // 20 m of card over 21 pixels at 10 m: pixel 10 is x = 0, each pixel ~0.95 m.
    let centre = film.pixel(0, 10, 10);
    assert!(centre.x > 0.1, "under the panel: {centre}");
    for x in [0, 1, 2, 3, 4, 5, 6, 7, 13, 14, 15, 16, 17, 18, 19, 20] {
        let v = film.pixel(0, x, 10);
        assert_eq!(v.x, 0.0, "pixel {x},10 outside the cone: {v}");
    }
}

#[test]
fn a_tinted_focus_fades_a_rect_light_to_its_tint_off_axis() {
    // focusColor = lerp(|cos θ|^focus, focusTint, white): with a tint (1, 0.25, 0) a
    // white light stays white on its axis and turns to orange-red off it, G/R =
    // 0.25 + 0.75·ff and B/R = ff, ff = cos⁴θ.
    let dir = Scratch::new("usd-focus-tint");
    let p = write(
        &dir,
        "tinted.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Camera "Cam"
{
    float focalLength = 20
    float horizontalAperture = 6
    float verticalAperture = 6
    double3 xformOp:translate = (0, 0, 10)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Mesh "Card"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0)]
    color3f[] primvars:displayColor = [(0.5, 0.5, 0.5)]
}
def RectLight "Tinted" (
    prepend apiSchemas = ["ShapingAPI"]
)
{
    float inputs:intensity = 5000
    float inputs:width = 0.02
    float inputs:height = 0.02
    float inputs:shaping:focus = 4
    color3f inputs:shaping:focusTint = (1, 0.25, 0)
    bool karma:light:renderlightgeo = false
    double3 xformOp:translate = (0, 0, 1)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
"#,
    );
    let mut desc = load(&p);
    let shaping = desc.lights[0].shaping.unwrap();
    assert_eq!((shaping.focus, shaping.focus_tint), (4.0, [1.0, 0.25, 0.0]));
    // 61 pixels over x in [-1.5, 1.5] m of the card (tan of the half view 3/20).
    let n = 61;
    desc.render.resolution = [n, n];
    desc.render.spp = 16;
    desc.render.max_depth = 2;
    let scene = Scene::build(&desc, &aov::assemble(Vec::new())).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp: 16,
            first_sample: 0,
        },
    );
    // Each sample's B/R is ff at its angle, so a pixel's ratio (of sums of samples that
    // are all positive in R) lies between the least and the greatest ff over the pixel's
    // footprint on the card and the light's 2 cm square.
    let ff = |tan: f64| (1.0 / (1.0 + tan * tan)).sqrt().powi(4);
    let pixel = 3.0 / n as f64;
    let half_light = 0.01;
    for x in [30u32, 40, 50, 58] {
        let x0 = x as f64 * pixel - 1.5;
        let (near, far) = (
            (x0 - half_light).max(0.0),
            (x0 + pixel + half_light).hypot(pixel / 2.0 + half_light),
        );
        let (lo, hi) = (ff(far), ff(near));
        let v = film.pixel(0, x, 30);
        assert!(v.x > 0.0, "pixel {x}: {v}");
        let (g, b) = ((v.y / v.x) as f64, (v.z / v.x) as f64);
        assert!(
            lo * 0.9999 <= b && b <= hi * 1.0001,
            "pixel {x}: B/R {b} outside [{lo}, {hi}]"
        );
        assert!(
            (g - (0.25 + 0.75 * b)).abs() < 1e-4,
            "pixel {x}: G/R {g}, B/R {b}"
        );
    }
    // On the axis the light is white; 1.5 m aside (56° off) it is orange-red.
    let far = film.pixel(0, 58, 30);
    assert!(far.z / far.x < 0.15 && far.y / far.x < 0.37, "{far}");
}

/// `SHOT` with two render products: `aovs.exr` (N, specular) before `beauty.exr` (Ci,
/// diffuseKey).
fn two_products() -> String {
    SHOT.replace(
        "rel products = </Render/Product>",
        "rel products = [</Render/Aovs>, </Render/Beauty>]",
    )
    .replace(
        r#"    def RenderProduct "Product"
    {
        rel orderedVars = [</Render/Vars/diffuseKey>, </Render/Vars/N>, </Render/Vars/Ci>, </Render/Vars/spec>]
        token productName = "shot_out.exr""#,
        r#"    def RenderProduct "Aovs"
    {
        rel orderedVars = [</Render/Vars/N>, </Render/Vars/spec>]
        token productName = "aovs.exr"
    }
    def RenderProduct "Beauty"
    {
        rel orderedVars = [</Render/Vars/Ci>, </Render/Vars/diffuseKey>]
        token productName = "beauty.exr""#,
    )
}

#[test]
fn each_render_product_is_a_file_with_exactly_its_vars() {
    use lightpath::job::RenderJob;
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;
    let dir = Scratch::new("usd-products");
    let scene = write(&dir, "shot.usda", &two_products());
    let desc = load(&scene);
    let products: Vec<(&str, Vec<&str>, bool)> = desc
        .products
        .iter()
        .map(|p| {
            (
                p.output.to_str().unwrap(),
                p.aovs.iter().map(String::as_str).collect(),
                p.beauty,
            )
        })
        .collect();
    assert_eq!(
        products,
        [
            ("aovs.exr", vec!["N", "specular"], false),
            ("beauty.exr", vec!["diffuseKey"], true)
        ]
    );
    let job = |out: &Path, cancelled: bool| {
        let mut job = RenderJob::new(scene.to_string_lossy());
        job.output = Some(out.to_path_buf());
        job.overrides.spp = Some(2);
        job.overrides.resolution = Some([16, 12]);
        job.aovs.light_groups = true;
        job.cancel = Some(Arc::new(AtomicBool::new(cancelled)));
        job
    };
    let silent = lightpath::progress::Silent;
    // -o naming a directory: each product there under its own name.
    let renders = dir.join("renders");
    std::fs::create_dir(&renders).unwrap();
    let summary = job(&renders, false)
        .prepare()
        .unwrap()
        .run(&silent)
        .unwrap();
    let (beauty, aovs) = (renders.join("beauty.exr"), renders.join("aovs.exr"));
    assert_eq!(
        summary.files,
        [aovs.clone(), beauty.clone(), renders.join("beauty.png")]
    );
    assert!(!renders.join("aovs.png").exists());
    let read = |p: &Path| lightpath::output::read_exr(p).unwrap();
    let names = |p: &Path| -> Vec<String> {
        let mut v: Vec<String> = read(p).aovs().into_iter().map(|a| a.0).collect();
        v.sort();
        v
    };
    assert_eq!(names(&aovs), ["N", "specular"]);
    assert_eq!(
        names(&beauty),
        [
            "beauty",
            "beauty__default",
            "beauty_fill",
            "beauty_key",
            "diffuseKey"
        ]
    );
    let a = read(&aovs);
    assert!(a.channel("R").is_none() && a.channel("A").is_none());
    assert_eq!(a.channels.len(), 6);
    assert!(read(&beauty).channel("A").is_some());
    for p in [&beauty, &aovs] {
        let (report, ok) = lightpath::post::partitions::report(p, 1e-4).unwrap();
        assert!(ok, "{report}");
    }
    assert!(read(&beauty)
        .attributes
        .iter()
        .any(|(k, v)| k == "lightpath/partition/beauty_key" && v == "lightgroups"));

    // -o naming a file: all in it, with a warning; the same pixels as the products'.
    let all = dir.join("all.exr");
    let prepared = job(&all, false).prepare().unwrap();
    assert!(
        prepared
            .warnings
            .iter()
            .any(|w| w.contains("aovs.exr, beauty.exr are written as one file")),
        "{:?}",
        prepared.warnings
    );
    prepared.run(&silent).unwrap();
    let whole = read(&all);
    for p in [&beauty, &aovs] {
        for (name, values) in &read(p).channels {
            let w = whole.channel(name).unwrap_or_else(|| panic!("{name}"));
            assert!(
                w.iter()
                    .zip(values)
                    .all(|(x, y)| x.to_bits() == y.to_bits()),
                "{name}"
            );
        }
    }

    // Interrupted: each product's rows done beside it, one checkpoint beside the beauty;
    // resumed, the products equal the uninterrupted ones.
    let again = dir.join("again");
    std::fs::create_dir(&again).unwrap();
    let stopped = job(&again, true).prepare().unwrap().run(&silent).unwrap();
    let checkpoint = stopped.interrupted.expect("stopped").checkpoint;
    assert_eq!(checkpoint.parent(), Some(again.as_path()));
    assert!(checkpoint.exists());
    assert!(again.join("aovs.partial.exr").exists() && again.join("beauty.partial.exr").exists());
    assert!(!again.join("beauty.exr").exists());
    let mut resume = job(&again, false);
    resume.resume = true;
    let prepared = resume.prepare().unwrap();
    assert!(prepared.resume.is_some());
    prepared.run(&silent).unwrap();
    assert!(!checkpoint.exists() && !again.join("aovs.partial.exr").exists());
    for name in ["beauty.exr", "aovs.exr"] {
        let (x, y) = (read(&again.join(name)), read(&renders.join(name)));
        assert_eq!(x.channels.len(), y.channels.len());
        for ((n, a), (_, b)) in x.channels.iter().zip(&y.channels) {
            assert!(
                a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits()),
                "{name} {n} differs after the resume"
            );
        }
    }
}

/// Every channel of `a` in `b`, bit for bit (`exact`) or to float rounding.
fn same_channels(a: &Path, b: &Path, exact: bool) {
    let (x, y) = (
        lightpath::output::read_exr(a).unwrap(),
        lightpath::output::read_exr(b).unwrap(),
    );
    let mut names: Vec<&String> = x.channels.iter().map(|c| &c.0).collect();
    let mut others: Vec<&String> = y.channels.iter().map(|c| &c.0).collect();
    names.sort();
    others.sort();
    assert_eq!(names, others, "{} against {}", a.display(), b.display());
    for (name, values) in &x.channels {
        let other = y.channel(name).unwrap();
        for (p, q) in values.iter().zip(other) {
            let ok = match exact {
                true => p.to_bits() == q.to_bits(),
                false => (p - q).abs() <= 1e-6 * p.abs().max(1.0),
            };
            assert!(ok, "{} {name}: {p} against {q}", a.display());
        }
    }
}

/// Runs `cmd`, which must succeed; its standard output.
fn run_ok(cmd: &mut std::process::Command) -> String {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// `scene` rendered with `args` into the directory `dir/single`, and as a farm job of two
/// parts split by `by` (through the fake sbatch) into `dir/<by>`: the two directories.
fn render_and_farm(
    dir: &Scratch,
    scene: &Path,
    args: &[&str],
    by: &str,
) -> (std::path::PathBuf, std::path::PathBuf) {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_lightpath");
    let single = dir.join("single");
    if !single.exists() {
        std::fs::create_dir(&single).unwrap();
        run_ok(
            Command::new(bin)
                .arg("render")
                .arg(scene)
                .args(args)
                .args(["--quiet", "-o"])
                .arg(&single),
        );
    }
    // `-o DIR/`: every product's file there, each merged from its own parts.
    let out = format!("{}/", dir.join(by).display());
    let script = run_ok(
        Command::new(bin)
            .args(["farm", "slurm"])
            .arg(scene)
            .args(["--tasks", "2", "--by", by, "-o", &out])
            .args(args),
    );
    let submit = dir.join(&format!("{by}.sh"));
    std::fs::write(&submit, &script).unwrap();
    run_ok(
        Command::new("bash")
            .arg(&submit)
            .env("PATH", crate::farm::fake_sbatch(dir))
            .env("SBATCH_STATE", dir.join(&format!("{by}.state"))),
    );
    (single, dir.join(by))
}

#[test]
fn a_farm_merges_each_render_product_into_its_own_file() {
    let dir = Scratch::new("usd-farm");
    let scene = write(&dir, "shot.usda", &two_products());
    let args = ["--spp", "4", "--resolution", "16x12", "--light-groups"];
    for by in ["tiles", "samples"] {
        let (single, farmed) = render_and_farm(&dir, &scene, &args, by);
        for name in ["aovs.exr", "beauty.exr"] {
            let merged = farmed.join(name);
            // Tiles are the single render's pixels exactly; sample ranges to rounding.
            same_channels(&single.join(name), &merged, by == "tiles");
            let (report, ok) = lightpath::post::partitions::report(&merged, 1e-4).unwrap();
            assert!(ok, "{report}");
        }
    }
}

/// `farm … --denoise -o DIR/` end to end: the tile parts merged per product, then each
/// product's file denoised, give exactly what `render --denoise -o DIR/` gives (tiles
/// merge to the single render's pixels, and the filter is deterministic).
#[cfg(feature = "denoise")]
#[test]
fn a_denoised_farm_gives_each_product_as_a_denoised_render_does() {
    let dir = Scratch::new("usd-farm-denoise");
    let scene = write(&dir, "shot.usda", &two_products());
    let args = [
        "--spp",
        "4",
        "--resolution",
        "16x12",
        "--light-groups",
        "--denoise",
    ];
    let (single, farm) = render_and_farm(&dir, &scene, &args, "tiles");
    for name in ["aovs.exr", "beauty.exr"] {
        let farmed = farm.join(name);
        let exr = lightpath::output::read_exr(&farmed).unwrap();
        assert!(
            exr.attributes
                .iter()
                .any(|(k, _)| k == lightpath::aov::naming::DENOISED_ATTRIBUTE),
            "{name} is not marked denoised"
        );
        same_channels(&single.join(name), &farmed, true);
        let (report, ok) = lightpath::post::partitions::report(&farmed, 1e-4).unwrap();
        assert!(ok, "{report}");
    }
}

#[cfg(feature = "denoise")]
#[test]
fn denoise_filters_each_render_products_file() {
    use lightpath::job::{DenoiseRequest, RenderJob};
    let dir = Scratch::new("usd-denoise-products");
    let scene = write(&dir, "shot.usda", &two_products());
    let render = |out: &Path, denoise: bool| {
        std::fs::create_dir(out).unwrap();
        let mut job = RenderJob::new(scene.to_string_lossy());
        job.output = Some(out.to_path_buf());
        job.overrides.spp = Some(4);
        job.overrides.resolution = Some([24, 18]);
        job.aovs.light_groups = true;
        job.denoise = denoise.then(DenoiseRequest::default);
        job.prepare()
            .unwrap()
            .run(&lightpath::progress::Silent)
            .unwrap()
    };
    let (noisy, clean) = (dir.join("noisy"), dir.join("clean"));
    render(&noisy, false);
    let summary = render(&clean, true);
    let said = summary.denoised.expect("denoised");
    for name in ["aovs.exr", "beauty.exr"] {
        let p = clean.join(name);
        assert!(said.contains(&p.display().to_string()), "{said}");
        let exr = lightpath::output::read_exr(&p).unwrap();
        assert!(
            exr.attributes
                .iter()
                .any(|(k, _)| k == lightpath::aov::naming::DENOISED_ATTRIBUTE),
            "{name} is not marked denoised"
        );
        let (report, ok) = lightpath::post::partitions::report(&p, 1e-4).unwrap();
        assert!(ok, "{name}: {report}");
        // Each file is what `lightpath denoise` makes of the noisy render's.
        let again = dir.join(&format!("again-{name}"));
        lightpath::post::denoise::run(&lightpath::post::denoise::DenoiseJob {
            input: noisy.join(name),
            output: again.clone(),
            keep_noisy: false,
            quality: Default::default(),
            preview_exposure: 0.0,
        })
        .unwrap();
        same_channels(&p, &again, true);
    }
    // The beauty's product has its preview; the AOVs' has none.
    assert!(clean.join("beauty.png").exists() && !clean.join("aovs.png").exists());
    // The specular AOV was filtered: it differs from the noisy render's.
    let (a, b) = (
        lightpath::output::read_exr(&noisy.join("aovs.exr")).unwrap(),
        lightpath::output::read_exr(&clean.join("aovs.exr")).unwrap(),
    );
    assert_ne!(a.channel("specular.G"), b.channel("specular.G"));
}

/// A floor seen from above, a sphere light to the side and a ball between them (out of
/// the camera's view) whose shadow covers the whole view; `{link}` goes on the light.
const SHADOW_LINK: &str = r#"#usda 1.0
(
    metersPerUnit = 1
)
def Camera "Cam"
{
    float focalLength = 50
    float horizontalAperture = 10
    float verticalAperture = 10
    double3 xformOp:translate = (0, 5, 0)
    float3 xformOp:rotateXYZ = (-90, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
}
def Mesh "Floor"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-5, 0, 5), (5, 0, 5), (5, 0, -5), (-5, 0, -5)]
    color3f[] primvars:displayColor = [(0.5, 0.5, 0.5)]
}
def Sphere "Blocker" ({active})
{
    double radius = 0.6
    double3 xformOp:translate = (2, 2, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def SphereLight "Lamp"
{
    float inputs:intensity = 50
    float inputs:radius = 0.5
    {link}
    double3 xformOp:translate = (4, 4, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
"#;

#[test]
fn shadow_linking_lets_light_pass_the_objects_it_excludes() {
    let dir = Scratch::new("usd-shadow-link");
    let stage = |name: &str, link: &str, active: bool| {
        let text = SHADOW_LINK.replace("{link}", link).replace(
            "{active}",
            if active {
                "active = true"
            } else {
                "active = false"
            },
        );
        load(&write(&dir, name, &text))
    };
    let excludes = "rel collection:shadowLink:excludes = </Blocker>";
    let linked = stage("linked.usda", excludes, true);
    assert_eq!(linked.lights[0].shadow_exclude, ["Blocker"]);
    assert_eq!(linked.lights[0].shadow_include, None);
    // ShadowAPI's switch: no object shadows the light.
    let off = stage("off.usda", "bool inputs:shadow:enable = false", true);
    assert_eq!(off.lights[0].shadow_include, Some(Vec::new()));
    // Only the floor casts shadows (an include list without the root).
    let only_floor = stage(
        "floor.usda",
        "uniform bool collection:shadowLink:includeRoot = 0\n    rel collection:shadowLink:includes = </Floor>",
        true,
    );
    let plain = stage("plain.usda", "", true);
    let removed = stage("removed.usda", "", false);

    // Direct diffuse light on the floor (C<RD>L: no light the ball passes on), in the
    // ball's shadow everywhere in view.
    let (w, spp) = (24u32, 16u32);
    let direct = |mut desc: SceneDesc| -> Vec<f32> {
        desc.render.resolution = [w, w];
        desc.render.spp = spp;
        let specs = aov::assemble([aov::AovSpec::new("direct", "C<RD>L")]);
        let scene = Scene::build(&desc, &specs).unwrap();
        let (film, _) = render(
            &scene,
            &RenderOptions {
                spp,
                first_sample: 0,
            },
        );
        (0..w * w).map(|i| film.pixel(1, i % w, i / w).x).collect()
    };
    let removed = direct(removed);
    let mean = |v: &[f32]| v.iter().map(|x| *x as f64).sum::<f64>() / v.len() as f64;
    // Pixel means differ by the render's noise: their mean difference is within five
    // standard errors of it.
    let agree = |a: &[f32], b: &[f32], what: &str| {
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| (*x - *y) as f64).collect();
        let m = d.iter().sum::<f64>() / d.len() as f64;
        let var = d.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (d.len() - 1) as f64;
        let se = (var / d.len() as f64).sqrt();
        assert!(m.abs() <= 5.0 * se + 1e-6, "{what}: {m} ± {se}");
    };
    let lit = mean(&removed);
    assert!(lit > 0.01, "{lit}");
    agree(&direct(linked), &removed, "the ball excluded");
    agree(&direct(off), &removed, "shadows off");
    agree(&direct(only_floor), &removed, "only the floor shadows");
    // Without linking the ball's shadow covers the view: the umbra has no direct light.
    let shadowed = mean(&direct(plain));
    assert!(shadowed < 1e-3 * lit, "{shadowed} vs {lit}");
}

#[test]
fn toml_lights_take_shadow_linking_keys() {
    let dir = Scratch::new("toml-shadow-link");
    let p = write(
        &dir,
        "s.toml",
        r#"
[[lights]]
type = "point"
position = [0, 1, 0]
intensity = [1, 1, 1]
shadow_include = ["floor"]
shadow_exclude = ["ball"]
"#,
    );
    let desc = lightpath::load_scene(p.to_str().unwrap()).unwrap();
    assert_eq!(
        desc.lights[0].shadow_include.as_deref(),
        Some(&["floor".to_string()][..])
    );
    assert_eq!(desc.lights[0].shadow_exclude, ["ball"]);
}

#[test]
fn a_shadow_linked_dome_lights_a_floor_under_a_roof_it_passes() {
    // A uniform dome of radiance 1 over a floor of albedo 0.5 under a wide roof that casts
    // no shadow from it: the floor's direct diffuse light is 0.5 (the dome's whole
    // hemisphere), which light sampling alone must give, as BSDF rays stop at the roof.
    let dir = Scratch::new("usd-shadow-dome");
    let p = write(
        &dir,
        "roof.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Camera "Cam"
{
    float focalLength = 50
    float horizontalAperture = 10
    float verticalAperture = 10
    double3 xformOp:translate = (0, 1, 0)
    float3 xformOp:rotateXYZ = (-90, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
}
def Mesh "Floor"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-5, 0, 5), (5, 0, 5), (5, 0, -5), (-5, 0, -5)]
    color3f[] primvars:displayColor = [(0.5, 0.5, 0.5)]
}
def Mesh "Roof"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-50, 2, 50), (50, 2, 50), (50, 2, -50), (-50, 2, -50)]
}
def DomeLight "Sky"
{
    float inputs:intensity = 1
    rel collection:shadowLink:excludes = </Roof>
}
"#,
    );
    let mut desc = load(&p);
    let (w, spp) = (16u32, 16u32);
    desc.render.resolution = [w, w];
    desc.render.spp = spp;
    let specs = aov::assemble([aov::AovSpec::new("direct", "C<RD>L")]);
    let scene = Scene::build(&desc, &specs).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp,
            first_sample: 0,
        },
    );
    let v: Vec<f64> = (0..w * w)
        .map(|i| film.pixel(1, i % w, i / w).x as f64)
        .collect();
    let m = v.iter().sum::<f64>() / v.len() as f64;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64;
    let se = (var / v.len() as f64).sqrt();
    assert!((m - 0.5).abs() <= 5.0 * se + 1e-4, "{m} ± {se}");
}

#[test]
fn a_distant_lights_angle_gives_the_penumbra_of_its_disc() {
    // A sun of 10° straight down, a half-plane 1 m over the floor with its edge over
    // x = 0, the camera under it looking down at the penumbra (x within ±0.1 m). Each
    // pixel's direct diffuse light is compared with the brute-force integral of the
    // disc's radiance over the directions the half-plane leaves open.
    let dir = Scratch::new("usd-sun-angle");
    let p = write(
        &dir,
        "sun.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
)
def Camera "Cam"
{
    float focalLength = 50
    float horizontalAperture = 20
    float verticalAperture = 1.25
    double3 xformOp:translate = (0, 0.5, 0)
    float3 xformOp:rotateXYZ = (-90, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
}
def Mesh "Floor"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-10, 0, 10), (10, 0, 10), (10, 0, -10), (-10, 0, -10)]
    color3f[] primvars:displayColor = [(0.5, 0.5, 0.5)]
}
def Mesh "Shade"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-10, 1, 10), (0, 1, 10), (0, 1, -10), (-10, 1, -10)]
}
def DistantLight "Sun"
{
    float inputs:intensity = 2
    bool inputs:normalize = true
    float inputs:angle = 10
    float3 xformOp:rotateXYZ = (-90, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:rotateXYZ"]
}
"#,
    );
    let mut desc = load(&p);
    assert!(matches!(desc.lights[0].kind, LightKind::Distant { angle, .. } if angle == 10.0));
    let (w, spp) = (32u32, 1024u32);
    desc.render.resolution = [w, 2];
    desc.render.spp = spp;
    let specs = aov::assemble([aov::AovSpec::new("direct", "C<RD>L")]);
    let scene = Scene::build(&desc, &specs).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp,
            first_sample: 0,
        },
    );
    // Brute force: the disc (radius 5°) on a grid of equal solid angles, the pixel's
    // footprint on a grid of floor points; radiance E/(π sin²α), albedo 0.5 over π.
    let (e, albedo, alpha) = (2.0f64, 0.5f64, 5f64.to_radians());
    let radiance = e / (std::f64::consts::PI * alpha.sin().powi(2));
    let one_minus_cos = 1.0 - alpha.cos();
    let (n_theta, n_phi, n_x) = (128, 128, 16);
    let cell = 2.0 * std::f64::consts::PI * one_minus_cos / (n_theta * n_phi) as f64;
    let lit_at = |x: f64| -> f64 {
        let mut sum = 0.0;
        for i in 0..n_theta {
            let cos_t = 1.0 - (i as f64 + 0.5) / n_theta as f64 * one_minus_cos;
            let sin_t = (1.0 - cos_t * cos_t).sqrt();
            for j in 0..n_phi {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n_phi as f64;
                // The direction up towards the disc, from the floor at x: where it
                // crosses the shade's height.
                if x + sin_t * phi.cos() / cos_t >= 0.0 {
                    sum += radiance * cos_t * cell;
                }
            }
        }
        albedo / std::f64::consts::PI * sum
    };
    let full = albedo * e / std::f64::consts::PI;
    let half_width = 0.5 * 0.2;
    let mut in_penumbra = 0;
    for px in 0..w {
        let expected = (0..n_x)
            .map(|k| {
                let u = (px as f64 + (k as f64 + 0.5) / n_x as f64) / w as f64;
                lit_at((2.0 * u - 1.0) * half_width)
            })
            .sum::<f64>()
            / n_x as f64;
        let got = (0..2).map(|y| film.pixel(1, px, y).x as f64).sum::<f64>() / 2.0;
        // Each sample is about `full` or 0: a Bernoulli's standard error over the
        // pixel pair's samples, plus the brute force's grid (1/128 of the disc's
        // radius per cell: 1 % of `full` at most at the steepest point).
        let p = (expected / full).clamp(0.0, 1.0);
        let se = full * (p * (1.0 - p) / (2 * spp) as f64).sqrt();
        assert!(
            (got - expected).abs() <= 5.0 * se + 0.01 * full,
            "pixel {px}: {got} vs {expected} (± {se})"
        );
        if p > 0.1 && p < 0.9 {
            in_penumbra += 1;
        }
    }
    // The penumbra (±tan 5° · 1 m) spans most of the view.
    assert!(in_penumbra >= w / 2, "{in_penumbra}");
}

/// A DomeLight's `portals` relationship names PortalLights: each becomes one of the
/// dome's portals, its rectangle (`width` × `height`, default the unit square) placed by
/// its transform; a target that is no PortalLight is warned about and left out. A dome
/// without portals keeps none.
#[test]
fn a_dome_light_reads_its_portal_lights() {
    let dir = Scratch::new("usd-portals");
    let path = write(
        &dir,
        "portals.usda",
        r#"#usda 1.0
(
    upAxis = "Y"
    metersPerUnit = 1
)
def DomeLight_1 "Sky"
{
    float inputs:intensity = 2
    rel portals = [</Window>, </Door>, </Nothing>]
}
def PortalLight "Window"
{
    float inputs:width = 2
    float inputs:height = 0.5
    double3 xformOp:translate = (3, 1, 0)
    float3 xformOp:rotateXYZ = (0, 90, 0)
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
}
def PortalLight "Door"
{
    double3 xformOp:translate = (0, 0, -2)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def DomeLight "Plain"
{
}
"#,
    );
    let desc = load(&path);
    let portals = |name: &str| match &desc
        .lights
        .iter()
        .find(|l| l.name.as_deref() == Some(name))
        .unwrap()
        .kind
    {
        LightKind::Dome { portals, .. } => portals.clone(),
        other => panic!("{name} is {other:?}"),
    };
    let sky = portals("Sky");
    assert_eq!(sky.len(), 2, "{sky:?}");
    let near = |a: [f32; 3], b: [f32; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-5);
    // The window: 2 wide along local X, turned 90° about Y (local X → −Z), at (3, 1, 0).
    let window = sky[0];
    assert!(near(window[0], [3.0, 0.75, 1.0]), "{window:?}");
    assert!(near(window[2], [3.0, 1.25, -1.0]), "{window:?}");
    // The door: the unit square at z = −2.
    assert!(near(sky[1][0], [-0.5, -0.5, -2.0]) && near(sky[1][2], [0.5, 0.5, -2.0]));
    assert!(portals("Plain").is_empty());
    assert!(
        desc.warnings.iter().any(|w| w.contains("/Nothing")),
        "{:?}",
        desc.warnings
    );
    // Portals are no lights of their own.
    assert_eq!(desc.lights.len(), 2);
}
