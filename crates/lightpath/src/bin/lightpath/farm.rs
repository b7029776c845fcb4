//! `lightpath farm`: a scheduler's script for the parts of one frame.

use crate::args::{FarmArgs, FarmCommand, RenderOnly};
use clap::Parser;

/// The farm script: the parts of the frame and the commands rendering and merging them.
pub(crate) fn farm_command(cmd: FarmCommand) -> Result<String, String> {
    use lightpath::farm::{absolute, split, FarmJob};
    type Printer = Box<dyn Fn(&FarmJob) -> String>;
    let (farm, render, script): (FarmArgs, Vec<String>, Printer) = match cmd {
        FarmCommand::Slurm {
            farm,
            sbatch,
            render,
        } => (
            farm,
            render,
            Box::new(move |job: &FarmJob| {
                FarmJob {
                    sbatch_args: sbatch.clone(),
                    ..job.clone()
                }
                .slurm_script()
            }),
        ),
        FarmCommand::Parallel { farm, jobs, render } => (
            farm,
            render,
            Box::new(move |job: &FarmJob| job.parallel_script(jobs.max(1))),
        ),
    };
    // The shared options must be valid render options, and leave the split to the farm.
    let parsed = RenderOnly::try_parse_from(
        ["lightpath render".to_string(), farm.scene.clone()]
            .into_iter()
            .chain(render.iter().cloned()),
    )
    .map_err(|e| format!("in the render options: {e}"))?
    .args;
    if parsed.output.is_some() || parsed.crop.is_some() || parsed.first_sample != 0 {
        return Err(
            "the farm chooses each part's --output, --crop and --first-sample: leave them out of the render options"
                .into(),
        );
    }
    let desc = lightpath::load_scene(&farm.scene).map_err(|e| e.to_string())?;
    // Several render products and -o a directory: every product's file there, as
    // `lightpath render -o DIR/` writes them (-o FILE.exr: all in that one file).
    let to_dir = {
        let o = &farm.output;
        o.as_os_str().to_string_lossy().ends_with('/')
            || (o.is_dir() && !o.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")))
    };
    let products: Vec<std::path::PathBuf> = if desc.products.len() > 1 && to_dir {
        lightpath::output::products::product_paths(&desc.products, Some(std::path::Path::new("")))
            .into_iter()
            .map(|p| p.exr)
            .collect()
    } else {
        Vec::new()
    };
    let mut settings = desc.render;
    parsed.settings.0.apply(&mut settings);
    let (spp, resolution) = (settings.spp, settings.resolution);
    let parts = split(farm.by, farm.tasks, spp, resolution)?;
    // The parts render noisy; only the merged frame is denoised.
    let (render, denoise) = lightpath::farm::split_denoise(
        &render,
        parsed.denoise,
        parsed.keep_noisy,
        parsed.denoise_quality.as_str(),
    );
    // Each sample range sets its own --spp; tiles all render the frame's.
    let mut render = lightpath::farm::without_option(&render, "--spp");
    if farm.by == lightpath::farm::SplitBy::Tiles {
        render.extend(["--spp".to_string(), spp.to_string()]);
    }
    // A built-in scene's name stays a name; a file becomes an absolute path.
    let scene = if std::path::Path::new(&farm.scene).exists() {
        absolute(std::path::Path::new(&farm.scene))
            .display()
            .to_string()
    } else {
        farm.scene.clone()
    };
    let job = FarmJob {
        lightpath: std::env::current_exe()
            .map_err(|e| format!("cannot locate the lightpath binary: {e}"))?,
        scene,
        render_args: render,
        parts,
        output: absolute(&farm.output),
        sbatch_args: Vec::new(),
        denoise,
        products,
    };
    Ok(script(&job))
}
