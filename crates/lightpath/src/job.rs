//! One render as the command line asks for it: load the scene, apply the overrides, plan
//! the AOVs, build, render, write the EXR and its PNG preview. The binary fills a
//! [`RenderJob`] from its arguments and prints what [`RenderJob::run`] returns; every
//! decision lives here or further down, so a script embedding the library gets the same
//! render as `lightpath render`.

use crate::aov::{self, AovSpec};
use crate::checkpoint::{self, Checkpoint, CheckpointError};
use crate::film::mattes::MatteTable;
use crate::film::{Film, PixelWindow};
use crate::identity::{Identity, Recording};
use crate::integrator::{FrameRequest, Snapshot};
use crate::output;
use crate::progress::Progress;
use crate::scene::desc::SceneDesc;
use crate::scene::{Scene, Source};
use crate::{Error, RenderOptions, RenderStats, Rendered, Resumable};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

mod checks;

/// Everything `lightpath render` can be told.
#[derive(Clone, Debug)]
pub struct RenderJob {
    /// A scene file or the name of a built-in scene.
    pub scene: String,
    /// Output EXR; `None`: `<scene stem>.exr` (or the USD stage's products) in the
    /// working directory. A directory (one that exists and is not named `.exr`, or a
    /// path ending in `/`): those default names in it. A file, for a stage of several products: all in that file.
    pub output: Option<PathBuf>,
    pub overrides: SettingOverrides,
    pub aovs: AovRequest,
    /// Index of the first sample (a farm's sample range).
    pub first_sample: u32,
    pub exr: output::ExrOptions,
    /// Exposure of the PNG preview, in stops.
    pub preview_exposure: f32,
    /// Which of the scene file's named cameras to render through (glTF); `None`: its
    /// first.
    pub camera: Option<String>,
    /// Render only this window of the frame (`--crop`); the EXR keeps the whole frame
    /// as its display window.
    pub crop: Option<PixelWindow>,
    /// Write Cryptomatte layers with this many ranks (`--cryptomatte`).
    pub cryptomatte: Option<u32>,
    /// Record the date in the header (`capDate`); off, identical renders are identical
    /// files.
    pub timestamp: bool,
    /// Continue from the checkpoint beside the output (`--resume`): the same command
    /// that was interrupted, plus this flag.
    pub resume: bool,
    /// With `resume`: when the checkpoint is of the scene before an edit (a file it read
    /// or an identity setting changed), start over instead of refusing
    /// (`--restart-if-changed`).
    pub restart_if_changed: bool,
    /// Write a checkpoint this often while rendering (`--checkpoint-every`).
    pub checkpoint_every: Option<std::time::Duration>,
    /// Set (by a SIGINT/SIGTERM handler) to stop after the rows in flight: the outputs
    /// then hold the rows done and a checkpoint is written beside them.
    pub cancel: Option<Arc<AtomicBool>>,
    /// Denoise the EXR after rendering (`render --denoise`; feature `denoise`).
    pub denoise: Option<DenoiseRequest>,
    /// What traces the rays (`--accel`): the BVH, or Embree (feature `embree`).
    pub accel: crate::geometry::Backend,
}

/// `render --denoise`: the written EXR is the denoised one (post/denoise.rs).
#[derive(Clone, Copy, Debug, Default)]
pub struct DenoiseRequest {
    /// Keep each filtered AOV's input as `<aov>_noisy`.
    pub keep_noisy: bool,
    pub quality: crate::post::denoise::Quality,
}

pub use crate::settings::SettingOverrides;

/// Which AOVs the command line asks for, besides the scene's own.
#[derive(Clone, Debug, Default)]
pub struct AovRequest {
    /// Add the standard set (docs/lpe.md#standard-aovs).
    pub standard: bool,
    /// The command line asked for the standard set (`--aovs standard`): added even to a
    /// USD stage whose render settings list its AOVs.
    pub standard_asked: bool,
    /// `NAME=DEFINITION` arguments.
    pub extra: Vec<String>,
    /// Bounce AOVs `bounce0 … bounce<K>plus`.
    pub bounces: Option<u32>,
    /// Split beauty per light group.
    pub light_groups: bool,
    /// Further AOVs to split per light group.
    pub light_group_aovs: Vec<String>,
    /// AOVs whose per-pixel variance to write as `<aov>_var` (besides the scene's).
    pub variance: Vec<String>,
}

/// A job whose scene is loaded, planned and built: ready to render, with what the user
/// should be told before the render starts.
pub struct PreparedRender {
    pub job: RenderJob,
    pub source: Source,
    pub scene: Scene,
    pub paths: output::naming::OutputPaths,
    /// A USD stage's render products, each a file of its own (empty: one file, `paths`,
    /// which is then the first product holding the beauty, beside which the checkpoint
    /// goes).
    pub products: Vec<output::products::ProductPlan>,
    pub warnings: Vec<String>,
    /// The window and Cryptomatte layers to render.
    pub frame: FrameRequest,
    /// The header attributes describing the scene and settings.
    pub metadata: Vec<(String, String)>,
    /// Everything the render read and the settings that decide its pixels.
    pub identity: Identity,
    /// The checkpoint `--resume` continues from.
    pub resume: Option<Checkpoint>,
}

/// What a finished render wrote and measured.
#[derive(Clone, Debug)]
pub struct RenderSummary {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel asked for: with adaptive sampling, the most a pixel took.
    pub spp: u32,
    /// Adaptive sampling: pixels took from `min_spp` to `spp` samples each.
    pub adaptive: bool,
    pub aovs: usize,
    pub stats: RenderStats,
    /// Accumulated values that overflowed to infinity (finite contributions too large to
    /// sum in 32 bits): those pixels are wrong, and the line says so.
    pub overflowed: u64,
    pub paths: output::naming::OutputPaths,
    /// Every file written: `paths`' pair, or each render product's EXR and, for those
    /// holding the beauty, its PNG.
    pub files: Vec<PathBuf>,
    /// Set when the render was stopped: rows finished of all rows, and the checkpoint
    /// written beside the outputs.
    pub interrupted: Option<Interrupted>,
    /// `render --denoise`: what the denoiser did (its summary line; one line per render
    /// product, naming its file, when there are several).
    pub denoised: Option<String>,
}

/// The two passes of an adaptive render (`integrator/adaptive.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdaptivePass {
    Pilot,
    Second,
}

impl Interrupted {
    /// `12 of 40 rows`, and for an adaptive render which pass's.
    pub fn rows_line(&self) -> String {
        let pass = match self.pass {
            None => "",
            Some(AdaptivePass::Pilot) => " of the pilot pass",
            Some(AdaptivePass::Second) => " of the second pass (the pilot pass is complete)",
        };
        format!("{} of {} rows{pass}", self.rows_done, self.rows)
    }
}

/// How far a stopped render got.
#[derive(Clone, Debug)]
pub struct Interrupted {
    /// Rows finished in the pass that was stopped.
    pub rows_done: u32,
    pub rows: u32,
    /// For an adaptive render, the pass that was stopped (its rows are that pass's).
    pub pass: Option<AdaptivePass>,
    pub checkpoint: PathBuf,
}

impl RenderSummary {
    /// The files written, for `wrote …`: `a.exr and a.png`, `b.exr, b.png and c.exr`.
    pub fn files_line(&self) -> String {
        RenderSummary::files_line_of(&self.files)
    }

    /// [`RenderSummary::files_line`] of a list of files.
    pub fn files_line_of(files: &[PathBuf]) -> String {
        let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
        match names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
            Some((last, _)) => last.clone(),
            None => String::new(),
        }
    }

    /// The one line `lightpath render` prints at the end.
    pub fn line(&self) -> String {
        let s = &self.stats;
        let mut dropped = if s.nonfinite > 0 {
            format!(", {} NaN/Inf contributions dropped", s.nonfinite)
        } else {
            String::new()
        };
        if self.overflowed > 0 {
            dropped += &format!(
                ", WARNING: {} pixel values overflowed to Inf (radiance too large for 32-bit floats)",
                self.overflowed
            );
        }
        let spp = if self.adaptive {
            let pixels = (self.width as u64 * self.height as u64).max(1);
            format!(
                "{:.1} spp on average (adaptive, at most {})",
                s.samples as f64 / pixels as f64,
                self.spp
            )
        } else {
            format!("{} spp", self.spp)
        };
        format!(
            "{}x{} at {spp}, {} AOVs: {:.2} s, {:.2} M samples/s, {:.2} M rays/s{dropped}",
            self.width,
            self.height,
            self.aovs,
            s.seconds,
            s.samples as f64 / s.seconds / 1e6,
            s.rays as f64 / s.seconds / 1e6,
        )
    }
}

impl RenderJob {
    /// A job rendering `scene` with its own settings and the standard AOVs.
    pub fn new(scene: impl Into<String>) -> RenderJob {
        RenderJob {
            scene: scene.into(),
            output: None,
            overrides: SettingOverrides::default(),
            aovs: AovRequest {
                standard: true,
                ..AovRequest::default()
            },
            first_sample: 0,
            exr: output::ExrOptions::default(),
            preview_exposure: 0.0,
            camera: None,
            crop: None,
            cryptomatte: None,
            timestamp: false,
            resume: false,
            restart_if_changed: false,
            checkpoint_every: None,
            cancel: None,
            denoise: None,
            accel: crate::geometry::Backend::Bvh,
        }
    }

    /// Loads the scene, applies the overrides, plans the AOVs and builds the scene.
    pub fn prepare(self) -> Result<PreparedRender, Error> {
        // Before the render: a build without denoising must not render for nothing.
        if self.denoise.is_some() && !crate::post::denoise::AVAILABLE {
            return Err(crate::error::PostError::DenoiseUnavailable.into());
        }
        if self.accel == crate::geometry::Backend::Embree
            && !crate::geometry::Backend::EMBREE_AVAILABLE
        {
            return Err(Error::Setting(
                crate::geometry::Backend::EMBREE_UNAVAILABLE.into(),
            ));
        }
        // Every file read from here to the built scene is an input of its identity.
        let recording = Recording::start();
        let source = crate::load_source(&self.scene)?;
        let usd_options = crate::scene::load::usd::UsdOptions {
            frame: self.overrides.frame.flatten().map(f64::from),
            render_settings: self.overrides.render_settings.clone().flatten(),
        };
        let mut desc = source.parse_with(&usd_options)?;
        if let Some(name) = &self.camera {
            desc.use_camera(name)?;
        }
        self.overrides.apply(&mut desc.render);
        checks::settings(&desc, self.first_sample)
            .map_err(|e| Error::Setting(format!("{}: {e}", desc.source)))?;
        let mut warnings = desc.warnings.clone();
        let (paths, product_paths) = self.output_paths(&desc, &mut warnings)?;
        warnings.extend(crate::scene::load::defaults::no_light_warning(&desc));
        let specs = self.plan(&desc, &mut warnings)?;
        crate::limits::Limits::current()
            .check_aovs(specs.len() as u64, "this render's AOV plan")?;
        let mut scene = Scene::build(&desc, &specs)?;
        let reads = recording.finish();
        // No output may replace a file the scene reads (its includes, meshes, textures).
        let mut inputs: Vec<&std::path::Path> = reads.iter().map(|r| r.path.as_path()).collect();
        inputs.push(std::path::Path::new(&self.scene));
        checks::outputs(&paths, &inputs).map_err(Error::Output)?;
        for p in &product_paths {
            checks::outputs(p, &inputs).map_err(Error::Output)?;
        }
        let products = match product_paths.is_empty() {
            true => Vec::new(),
            false => output::products::assign(&desc.products, &product_paths, &scene.aovs),
        };
        let identity = Identity::new(
            &source.dir,
            &reads,
            crate::identity::settings(&desc, self.camera.as_deref()),
        );
        scene.accel.use_backend(self.accel)?;
        scene.variance_aovs = self.variance_aovs(&desc, &scene)?;
        checks::film(&scene)?;
        warnings.extend(checks::scene_warnings(&scene));
        for w in scene.automaton.warnings() {
            let aov = &scene.aovs[w.rule.0 as usize];
            warnings.push(format!(
                "AOV '{}' ({}): {}",
                aov.name, aov.definition, w.message
            ));
        }
        let (width, height) = (scene.camera.width, scene.camera.height);
        let window = self.crop.unwrap_or(PixelWindow::full(width, height));
        window.check(width, height).map_err(|e| Error::Plan(e.0))?;
        let metadata = output::naming::settings_attributes(&scene, &identity, window);
        let mattes = self
            .cryptomatte
            .map(|ranks| matte_table(&desc, &scene, ranks));
        let checkpoint_path = checkpoint::path_for(&paths.exr);
        let resume = self.checkpoint(
            &checkpoint_path,
            (&scene, &identity),
            window,
            mattes.is_some(),
            &mut warnings,
        )?;
        Ok(PreparedRender {
            job: self,
            source,
            scene,
            paths,
            products,
            warnings,
            frame: FrameRequest { window, mattes },
            metadata,
            identity,
            resume,
        })
    }

    /// Where the render goes: its file (for several products, the first holding the
    /// beauty: the checkpoint goes beside it) and each product's (empty: one file).
    #[allow(clippy::type_complexity)]
    fn output_paths(
        &self,
        desc: &SceneDesc,
        warnings: &mut Vec<String>,
    ) -> Result<
        (
            output::naming::OutputPaths,
            Vec<output::naming::OutputPaths>,
        ),
        Error,
    > {
        let dir = self
            .output
            .as_deref()
            // A directory named like an EXR (`-o shot.exr` where one is) is a mistake,
            // refused by the output checks.
            .filter(|p| {
                p.as_os_str().to_string_lossy().ends_with('/')
                    || (p.is_dir() && !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")))
            });
        let several = desc.products.len() > 1;
        if several && (dir.is_some() || self.output.is_none()) {
            let paths = output::products::product_paths(&desc.products, dir);
            for (i, p) in paths.iter().enumerate() {
                if let Some(j) = paths[..i].iter().position(|q| q.exr == p.exr) {
                    return Err(Error::Setting(format!(
                        "{}: render products {} and {} are both written to {}",
                        desc.source,
                        j + 1,
                        i + 1,
                        p.exr.display()
                    )));
                }
            }
            let primary = desc.products.iter().position(|p| p.beauty).unwrap_or(0);
            return Ok((paths[primary].clone(), paths));
        }
        if several {
            let names: Vec<String> = desc
                .products
                .iter()
                .map(|p| p.output.display().to_string())
                .collect();
            warnings.push(format!(
                "{}: the render products {} are written as one file, -o {} (give -o a \
                 directory to write each product there)",
                desc.source,
                names.join(", "),
                self.output
                    .as_deref()
                    .unwrap_or(std::path::Path::new(""))
                    .display()
            ));
        }
        let own = match dir {
            Some(d) => {
                let name = output::naming::output_paths(&self.scene, desc.output.as_deref()).exr;
                Some(d.join(name.file_name().unwrap_or(name.as_os_str())))
            }
            None => self.output.clone().or(desc.output.clone()),
        };
        Ok((
            output::naming::output_paths(&self.scene, own.as_deref()),
            Vec::new(),
        ))
    }

    /// The checkpoint `--resume` continues from: refused when it is not of this render,
    /// unless the scene changed and the job may start over (`restart_if_changed`). Without
    /// `--resume`, a checkpoint there is a warning: this render replaces it.
    fn checkpoint(
        &self,
        checkpoint_path: &std::path::Path,
        (scene, identity): (&Scene, &Identity),
        window: PixelWindow,
        mattes: bool,
        warnings: &mut Vec<String>,
    ) -> Result<Option<Checkpoint>, Error> {
        if !self.resume {
            if checkpoint_path.exists() {
                warnings.push(format!(
                    "{} is there from an interrupted render: this render starts afresh and \
                     replaces it (add --resume to continue it instead)",
                    checkpoint_path.display()
                ));
            }
            return Ok(None);
        }
        if mattes {
            return Err(Error::Setting(
                "--resume with --cryptomatte: a checkpoint does not hold Cryptomatte \
                 layers; render again without --resume"
                    .into(),
            ));
        }
        if !checkpoint_path.exists() {
            return Err(Error::Setting(format!(
                "--resume: there is no checkpoint {} (it is written when a render is \
                 interrupted, or with --checkpoint-every)",
                checkpoint_path.display()
            )));
        }
        let stamp = checkpoint::Stamp {
            identity,
            fingerprint: fingerprint(scene, self.first_sample, window),
        };
        let shape = checkpoint::FilmShape {
            width: window.width(),
            height: window.height(),
            aovs: scene.aovs.len(),
            spp: scene.settings.spp,
            squared: scene.variance_aovs.clone(),
            adaptive: scene.settings.noise_threshold > 0.0,
        };
        match checkpoint::read(checkpoint_path, stamp, shape) {
            Ok(checkpoint) => Ok(Some(checkpoint)),
            Err(e @ CheckpointError::SceneChanged { .. }) if self.restart_if_changed => {
                warnings.push(format!("{e}: starting over (--restart-if-changed)"));
                Ok(None)
            }
            Err(e) => Err(Error::Setting(e.to_string())),
        }
    }

    /// The AOVs whose variance is written: the command line's and the scene's, by name
    /// (light-group parts included), each once.
    fn variance_aovs(&self, desc: &SceneDesc, scene: &Scene) -> Result<Vec<u32>, Error> {
        let mut out: Vec<u32> = Vec::new();
        for name in self.aovs.variance.iter().chain(&desc.variance) {
            let k = scene
                .aovs
                .iter()
                .position(|a| &a.name == name)
                .ok_or_else(|| {
                    Error::Plan(format!(
                        "--variance names '{name}', which is not an AOV of this render{}",
                        crate::suggest::did_you_mean(
                            name,
                            scene.aovs.iter().map(|a| a.name.as_str())
                        )
                    ))
                })?;
            let var = crate::aov::naming::variance_name(name);
            if scene.aovs.iter().any(|a| a.name == var) {
                return Err(Error::Plan(format!(
                    "the variance of '{name}' would be named '{var}', which is already an AOV"
                )));
            }
            if !out.contains(&(k as u32)) {
                out.push(k as u32);
            }
        }
        Ok(out)
    }

    /// The AOV plan from the request and the scene description.
    fn plan(&self, desc: &SceneDesc, warnings: &mut Vec<String>) -> Result<Vec<AovSpec>, Error> {
        let request = aov::plan::PlanRequest {
            standard: self.aovs.standard
                && (self.aovs.standard_asked || desc.standard_aovs != Some(false)),
            scene_aovs: desc
                .aovs
                .iter()
                .map(|(n, d)| (n.clone(), d.definition.clone()))
                .collect(),
            extra: aov::plan::parse_aov_args(&self.aovs.extra)
                .map_err(|e| Error::Plan(e.to_string()))?,
            bounces: self.aovs.bounces,
            split: self.aovs.light_group_aovs.clone(),
            scene_split: desc.light_group_aovs.clone(),
            light_groups: self.aovs.light_groups || desc.light_groups,
            scene_light_groups: desc
                .lights
                .iter()
                .flat_map(|l| l.groups.iter().cloned())
                .collect(),
        };
        let plan = aov::plan::AovPlan::build(&request).map_err(|e| Error::Plan(e.to_string()))?;
        warnings.extend(plan.warnings.iter().map(|w| w.to_string()));
        Ok(plan.specs)
    }
}

/// The Cryptomatte table of a scene: each object's name, its material's name and its
/// asset (the `asset` key, else its own name). Holdouts get none: they are not seen.
fn matte_table(desc: &SceneDesc, scene: &Scene, ranks: u32) -> MatteTable {
    use crate::post::cryptomatte::{ASSET, MATERIAL, OBJECT};
    let material_names: Vec<&String> = desc.materials.keys().collect();
    let names: Vec<Vec<Option<String>>> = scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            if o.holdout {
                return vec![None, None, None];
            }
            let material = o
                .material
                .and_then(|m| material_names.get(m as usize))
                .map(|n| n.to_string());
            let asset = desc
                .objects
                .get(i)
                .and_then(|d| d.asset.clone())
                .unwrap_or_else(|| o.name.clone());
            vec![Some(o.name.clone()), material, Some(asset)]
        })
        .collect();
    crate::post::cryptomatte::table(
        vec![OBJECT.into(), MATERIAL.into(), ASSET.into()],
        ranks,
        &names,
    )
}

impl PreparedRender {
    /// Renders (the rows a resumed checkpoint does not hold), then writes the EXR and its
    /// PNG preview together. A render stopped through `cancel` writes the rows done and a
    /// checkpoint beside the outputs; a finished one removes the checkpoint.
    pub fn run(self, progress: &dyn Progress) -> Result<RenderSummary, Error> {
        let PreparedRender {
            job,
            source,
            scene,
            paths,
            products,
            frame,
            metadata,
            identity,
            resume,
            ..
        } = self;
        let options = RenderOptions {
            spp: scene.settings.spp,
            first_sample: job.first_sample,
        };
        let checkpoint_path = checkpoint::path_for(&paths.exr);
        let stamp = checkpoint::Stamp {
            identity: &identity,
            fingerprint: fingerprint(&scene, job.first_sample, frame.window),
        };
        let mut last_checkpoint = std::time::Instant::now();
        let mut checkpoint_error = None;
        let mut save = |snapshot: &Snapshot| {
            let Some(every) = job.checkpoint_every else {
                return;
            };
            let unfinished = snapshot.pilot.is_some_and(|p| !p.complete)
                || !snapshot.rows_done.iter().all(|d| *d);
            if last_checkpoint.elapsed() >= every && unfinished {
                if let Err(e) = checkpoint::write(&checkpoint_path, stamp, snapshot) {
                    checkpoint_error.get_or_insert(e);
                }
                last_checkpoint = std::time::Instant::now();
            }
        };
        let (film, rows_done, pilot, splats) = resume.map_or((None, Vec::new(), None, None), |c| {
            (Some(c.film), c.rows_done, c.pilot, c.splats)
        });
        let rendered = crate::integrator::render_resumable(
            &scene,
            &options,
            &frame,
            progress,
            Resumable {
                film,
                rows_done,
                pilot,
                splats,
                cancel: job.cancel.as_deref(),
                after_band: Some(&mut save),
                // Checkpoints come between bands: about 64 of them per frame.
                max_band_rows: job
                    .checkpoint_every
                    .map(|_| (frame.window.height() as usize).div_ceil(64)),
            },
        );
        if let Some(e) = checkpoint_error {
            return Err(Error::Output(e));
        }
        let complete = rendered.finished();
        let Rendered {
            mut film,
            stats,
            rows_done,
            pilot,
            splats,
        } = rendered;
        let interrupted = (!complete)
            .then(|| Interrupted::of(&film, &rows_done, pilot.as_ref(), &checkpoint_path));
        if interrupted.is_some() {
            let done = (rows_done.as_slice(), pilot.as_ref(), splats);
            keep_interrupted(&checkpoint_path, stamp, &mut film, done)?;
        }
        let overflowed = non_finite_values(&film);
        let header = exr_header(&job, &source, &scene, metadata, &film, interrupted.as_ref());
        // Unfinished rows go beside the output, never over a finished image of that name.
        let partial = output::naming::partial_paths(&paths);
        let written = interrupted.as_ref().map_or(paths, |_| partial.clone());
        let (width, height, spp) = (film.width, film.height, film.spp);
        let files = if products.is_empty() {
            let derived = output::derived_aovs(&film, &scene.aovs);
            let png = output::stage_png(&written.png, &film, 0, job.preview_exposure)
                .map_err(Error::Output)?;
            let exr = output::stage_film(&written.exr, film, &scene.aovs, derived, job.exr, header)
                .map_err(Error::Output)?;
            output::atomic::commit_pair(exr, png).map_err(Error::Output)?;
            vec![written.exr.clone(), written.png.clone()]
        } else {
            write_products(&products, film, &scene, &job, header, interrupted.is_some())?
        };
        if interrupted.is_none() {
            remove_leftovers(&checkpoint_path, &partial, &products)?
        }
        let paths = written;
        // An interrupted render's rows are unfinished: it is denoised once it is resumed.
        let denoised = (job.denoise)
            .filter(|_| interrupted.is_none())
            .map(|d| denoise_outputs(&paths, &products, d, job.preview_exposure, progress))
            .transpose()?;
        Ok(RenderSummary {
            width,
            height,
            spp,
            adaptive: scene.settings.noise_threshold > 0.0,
            aovs: scene.aovs.len(),
            stats,
            overflowed,
            paths,
            files,
            interrupted,
            denoised,
        })
    }
}

/// Writes an interrupted render's checkpoint: its film, rows, pilot and light tracing's
/// splats, which the film then takes (the partial picture shows what light tracing found
/// so far; the checkpoint keeps it apart: film/splats.rs).
fn keep_interrupted(
    path: &std::path::Path,
    stamp: checkpoint::Stamp,
    film: &mut Film,
    (rows_done, pilot, splats): (
        &[bool],
        Option<&crate::integrator::adaptive::Pilot>,
        Option<crate::film::splats::Splats>,
    ),
) -> Result<(), Error> {
    let snapshot = Snapshot {
        film,
        rows_done,
        pilot,
        splats: splats.as_ref(),
    };
    checkpoint::write(path, stamp, &snapshot).map_err(Error::Output)?;
    if let Some(s) = &splats {
        s.add_to(film);
    }
    Ok(())
}

/// A finished render's checkpoint and the interrupted render's partial images (its own
/// and each product's): out of date, removed.
fn remove_leftovers(
    checkpoint: &std::path::Path,
    partial: &output::naming::OutputPaths,
    products: &[output::products::ProductPlan],
) -> Result<(), Error> {
    remove_checkpoint(checkpoint)?;
    let mut stale = vec![partial.exr.clone(), partial.png.clone()];
    for plan in products {
        let p = output::naming::partial_paths(&plan.paths);
        stale.extend([p.exr, p.png]);
    }
    for stale in &stale {
        remove_stale(stale)?;
    }
    Ok(())
}

/// Writes each render product's file, cut from the film (its `.partial` name when the
/// render was stopped); every product staged before any is renamed into place, so a
/// product that cannot be written leaves the others' old files too. Returns the files.
fn write_products(
    products: &[output::products::ProductPlan],
    film: Film,
    scene: &Scene,
    job: &RenderJob,
    header: output::ExrHeader,
    interrupted: bool,
) -> Result<Vec<PathBuf>, Error> {
    let mut files = Vec::new();
    let mut staged = Vec::new();
    for plan in products {
        let (sub, aovs) = output::products::product_film(&film, &scene.aovs, plan);
        let to = match interrupted {
            true => output::naming::partial_paths(&plan.paths),
            false => plan.paths.clone(),
        };
        let beauty = aovs
            .iter()
            .position(|a| a.name == crate::aov::naming::BEAUTY);
        let png = match beauty {
            Some(k) if plan.beauty => Some(
                output::stage_png(&to.png, &sub, k, job.preview_exposure).map_err(Error::Output)?,
            ),
            _ => None,
        };
        let derived = output::derived_aovs(&sub, &aovs);
        let exr = output::stage_film(&to.exr, sub, &aovs, derived, job.exr, header.clone())
            .map_err(Error::Output)?;
        files.push(to.exr);
        if png.is_some() {
            files.push(to.png);
        }
        staged.push((exr, png));
    }
    drop(film);
    for (exr, png) in staged {
        match png {
            Some(png) => output::atomic::commit_pair(exr, png),
            None => exr.commit(),
        }
        .map_err(Error::Output)?;
    }
    Ok(files)
}

impl Interrupted {
    /// How far a render stopped before its end got: its finished rows, its adaptive pass,
    /// and the checkpoint written for `--resume`.
    fn of(
        film: &Film,
        rows_done: &[bool],
        pilot: Option<&crate::integrator::adaptive::Pilot>,
        checkpoint: &std::path::Path,
    ) -> Interrupted {
        Interrupted {
            rows_done: rows_done.iter().filter(|d| **d).count() as u32,
            rows: film.height,
            pass: pilot.map(|p| match p.complete {
                false => AdaptivePass::Pilot,
                true => AdaptivePass::Second,
            }),
            checkpoint: checkpoint.to_path_buf(),
        }
    }
}

/// Values of the film that overflowed to infinity or NaN (the summary reports them).
fn non_finite_values(film: &Film) -> u64 {
    film.planes
        .iter()
        .map(|p| p.iter().filter(|v| !v.is_finite()).count() as u64)
        .sum()
}

/// The EXR header of a render: its settings, the AOVs' metadata, the camera, the date if
/// asked, and how far an interrupted render got.
fn exr_header(
    job: &RenderJob,
    source: &Source,
    scene: &Scene,
    metadata: Vec<(String, String)>,
    film: &Film,
    interrupted: Option<&Interrupted>,
) -> output::ExrHeader {
    let mut text = output::naming::RenderMetadata {
        scene: source.name.clone(),
        spp: scene.settings.spp,
        first_sample: job.first_sample,
    }
    .attributes();
    text.extend(metadata);
    if let Some(i) = interrupted {
        let per_row = film.width as u64 * film.spp as u64;
        let samples = match &film.sample_counts {
            // Adaptive: how many pixels will take is not known yet.
            Some(counts) => format!(
                "{} samples so far",
                counts.iter().map(|&n| n as u64).sum::<u64>()
            ),
            None => format!(
                "{} of {} samples",
                i.rows_done as u64 * per_row,
                i.rows as u64 * per_row
            ),
        };
        let rest = if i.pass.is_some() {
            "the other pixels hold only their pilot samples or none"
        } else {
            "the other rows are empty"
        };
        text.push((
            crate::aov::naming::INTERRUPTED_ATTRIBUTE.to_string(),
            format!(
                "{} rendered ({samples}); {rest}: run the same command with --resume to finish",
                i.rows_line()
            ),
        ));
    }
    let capture_date = job.timestamp.then(|| {
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        output::naming::capture_date(now)
    });
    output::ExrHeader {
        world_to_camera: Some(scene.camera.world_to_camera().to_cols_array()),
        world_to_ndc: Some(scene.camera.world_to_ndc().to_cols_array()),
        capture_date,
        text,
        ..output::ExrHeader::default()
    }
}

/// A finished render's checkpoint is stale: removed (none there is fine).
fn remove_checkpoint(path: &std::path::Path) -> Result<(), Error> {
    remove_if_there(path, "the finished render's checkpoint")
}

/// An interrupted render's `.partial` image, out of date once the render has finished.
fn remove_stale(path: &std::path::Path) -> Result<(), Error> {
    remove_if_there(path, "the interrupted render's partial image")
}

fn remove_if_there(path: &std::path::Path, what: &'static str) -> Result<(), Error> {
    match std::fs::remove_file(path) {
        Err(source) if source.kind() != std::io::ErrorKind::NotFound => {
            Err(Error::Output(crate::error::OutputError::Remove {
                what,
                path: path.to_path_buf(),
                source,
            }))
        }
        _ => Ok(()),
    }
}

/// What a checkpoint must match to be resumed besides the scene's identity: the rest of
/// the job (the settings after overrides, the film and window, the sample range, the
/// AOVs).
fn fingerprint(scene: &Scene, first_sample: u32, window: PixelWindow) -> u64 {
    let settings: String = crate::settings::all_pairs(&scene.settings)
        .iter()
        .map(|(k, v)| format!("{k}={v}\n"))
        .collect();
    let settings = format!(
        "{settings}{}x{} first {first_sample} window {:?}",
        scene.camera.width, scene.camera.height, window
    );
    let aovs: String = scene
        .aovs
        .iter()
        .map(|a| format!("{}={}\n", a.name, a.definition))
        .collect();
    checkpoint::fingerprint(&[settings.as_bytes(), aovs.as_bytes()])
}

/// Denoises a finished render's EXR, or each render product's file as a render of that
/// product alone would be (its beauty at the beauty's quality, its AOVs at theirs, its
/// own partitions reconciled): the summary line, one per product naming its file.
fn denoise_outputs(
    paths: &output::naming::OutputPaths,
    products: &[output::products::ProductPlan],
    request: DenoiseRequest,
    exposure: f32,
    progress: &dyn Progress,
) -> Result<String, Error> {
    if products.is_empty() {
        return denoise_in_place(paths, request, exposure, progress);
    }
    let mut lines = Vec::new();
    for plan in products {
        let line = denoise_in_place(&plan.paths, request, exposure, progress)?;
        lines.push(format!("{}: {line}", plan.paths.exr.display()));
    }
    Ok(lines.join("\n"))
}

/// Replaces a render's EXR by its denoised version and its preview by the denoised beauty.
fn denoise_in_place(
    paths: &output::naming::OutputPaths,
    request: DenoiseRequest,
    exposure: f32,
    progress: &dyn Progress,
) -> Result<String, Error> {
    let job = crate::post::denoise::DenoiseJob {
        input: paths.exr.clone(),
        output: paths.exr.clone(),
        keep_noisy: request.keep_noisy,
        quality: request.quality,
        preview_exposure: exposure,
    };
    let summary = crate::post::denoise::run_with_progress(&job, progress)?;
    Ok(summary.line())
}
