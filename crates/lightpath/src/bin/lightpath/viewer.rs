//! `lightpath view` and `render --preview`: the browser page, and waiting for Ctrl-C.

use crate::args::ServeArgs;
use lightpath::progress::Progress;
use lightpath::view;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// Starts the viewer on `data`, prints its URL and opens a browser unless told not to.
pub(crate) fn start_viewer(
    data: view::ViewData,
    exr: Option<PathBuf>,
    serve: &ServeArgs,
) -> Result<view::Viewer, String> {
    let viewer = view::Viewer::start(data, exr, serve.port)?;
    say!("viewing at {}", viewer.url());
    if !serve.no_open && !view::open_browser(&viewer.url()) {
        tell!("no browser opener found (xdg-open, open): open the URL yourself");
    }
    Ok(viewer)
}

/// Blocks until Ctrl-C (SIGINT, or SIGTERM).
pub(crate) fn wait_for_ctrl_c() {
    if let Err(e) = lightpath::interrupt::wait() {
        tell!("warning: {e}; stop with another signal");
        loop {
            std::thread::park();
        }
    }
}

pub(crate) fn view_command(exr: PathBuf, serve: &ServeArgs) -> ExitCode {
    // Before the URL is printed: a Ctrl-C right after it must stop the viewer cleanly.
    if let Err(e) = lightpath::interrupt::catch() {
        tell!("warning: {e}");
    }
    let data = match view::open(&exr) {
        Ok(d) => d,
        Err(e) => {
            tell!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let viewer = match start_viewer(data, Some(exr), serve) {
        Ok(v) => v,
        Err(e) => {
            tell!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    say!("press Ctrl-C to stop");
    wait_for_ctrl_c();
    viewer.stop();
    say!("stopped");
    ExitCode::SUCCESS
}

/// `render --preview`: the viewer fed by the render, then showing the written EXR.
pub(crate) fn render_with_preview(
    prepared: lightpath::job::PreparedRender,
    progress: &dyn Progress,
    serve: &ServeArgs,
) -> ExitCode {
    let data = view::preview::live_data(&prepared.scene, prepared.source.name.clone());
    let height = prepared.scene.camera.height;
    let viewer = match start_viewer(data, None, serve) {
        Ok(v) => v,
        Err(e) => {
            tell!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let preview = view::preview::LivePreview::new(progress, viewer.shared().clone(), height);
    let summary = prepared.run(&preview);
    // From here a Ctrl-C stops the viewer.
    lightpath::interrupt::render_finished();
    let summary = match summary {
        Ok(s) => s,
        Err(e) => {
            tell!("error: {e}");
            viewer.stop();
            return ExitCode::FAILURE;
        }
    };
    say!("{}", summary.line());
    say!(
        "wrote {} and {}",
        summary.paths.exr.display(),
        summary.paths.png.display()
    );
    match view::open(&summary.paths.exr) {
        Ok(data) => viewer.shared().show_file(data, summary.paths.exr.clone()),
        Err(e) => tell!("warning: cannot show the written EXR: {e}"),
    }
    say!("still viewing at {}; press Ctrl-C to stop", viewer.url());
    wait_for_ctrl_c();
    viewer.stop();
    say!("stopped");
    ExitCode::SUCCESS
}
