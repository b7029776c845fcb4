//! `lightpath view`: a page on 127.0.0.1 that shows every AOV of an EXR with its
//! expression, grouped by the partitions its header declares (each with its measured
//! error), a large view with exposure, channels and a pixel inspector, a light-group
//! mixer running on the GPU, and "Save comp" through `post::comp::run`, the code behind
//! `lightpath comp`. `render --preview` serves the same page while a render fills it
//! (see [`preview`]).
//!
//! The page (`page/`) is plain HTML, JS and CSS compiled into the binary. It asks for
//! what it shows, as half floats: thumbnails box-filtered on the server, the AOV in the
//! large view at full size (see docs/performance.md for the figures on a 1080p file with
//! 40 AOVs).
//!
//! API (all GET but the comp):
//! - `/api/info`: the AOVs, partitions, mixers, Cryptomatte layers, `_noisy` twins (JSON)
//! - `/api/image?name=N&width=W`: AOV or Cryptomatte layer `N`, at most `W` pixels across
//!   (half floats, RGB interleaved, rows top down; size in `X-Width`, `X-Height`)
//! - `/api/pixel?x=X&y=Y`: every AOV's value at a pixel, and the objects under it (JSON)
//! - `/api/matte?layer=L&id=HEX`: an object's Cryptomatte matte (one half-float channel)
//! - `POST /api/comp` `{"gains": ["key=0.5"], "base": "beauty", "output": "relit.exr",
//!   "exposure": 0}`: writes the comp beside the EXR, answers its paths and the
//!   equivalent `lightpath comp` command line.
//!
//! Only requests whose `Host` is this server's own address are answered (no DNS
//! rebinding), and the comp must be posted as JSON (a cross-site form cannot).

mod crypto;
mod data;
mod http;
pub mod preview;

pub use data::{downsample, HalfImage, ViewData, NOISY_SUFFIX, THUMBNAIL_WIDTH};

use crate::post::comp::CompJob;
use http::{Request, Response};
use serde::Deserialize;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, RwLock};

const INDEX_HTML: &str = include_str!("page/index.html");
const APP_JS: &str = include_str!("page/app.js");
const STYLE_CSS: &str = include_str!("page/style.css");

/// What the server threads share: the data shown and the EXR file behind it.
pub struct Shared {
    data: RwLock<ViewData>,
    /// The EXR as the user named it: comp's input and the command line shown. `None`
    /// while a live render has not written it yet.
    exr: Mutex<Option<PathBuf>>,
    /// The server's port, set once it listens.
    port: Arc<std::sync::OnceLock<u16>>,
    /// A thread is making thumbnails or measuring the partition checks.
    measuring: AtomicBool,
}

impl Shared {
    /// Runs `f` on the data for writing (a live render's bands).
    pub fn update<R>(&self, f: impl FnOnce(&mut ViewData) -> R) -> R {
        let mut data = self.data.write().unwrap_or_else(|e| e.into_inner());
        f(&mut data)
    }

    /// Replaces what is shown by an EXR file (a finished render's).
    pub fn show_file(&self, data: ViewData, exr: PathBuf) {
        let mut old = self.data.write().unwrap_or_else(|e| e.into_inner());
        let generation = old.generation + 1;
        *old = data;
        old.generation = generation;
        *self.exr.lock().unwrap_or_else(|e| e.into_inner()) = Some(exr);
    }
}

/// A running viewer: the HTTP server and what it shows.
pub struct Viewer {
    http: http::Server,
    shared: Arc<Shared>,
}

/// Reads an EXR for viewing.
pub fn open(path: &Path) -> Result<ViewData, crate::error::ExrReadError> {
    let exr = crate::output::read_exr(path)?;
    let title = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    Ok(ViewData::new(exr, title))
}

impl Viewer {
    /// Serves `data` on 127.0.0.1:`port` (0: a free port the system picks). `exr` is the
    /// file the data came from, if any (comps need it).
    pub fn start(
        data: ViewData,
        exr: Option<PathBuf>,
        port: u16,
    ) -> Result<Viewer, crate::error::ViewError> {
        // The handler needs the port (to check Host) before the server has one.
        let port_cell = Arc::new(std::sync::OnceLock::new());
        let shared = Arc::new(Shared {
            data: RwLock::new(data),
            exr: Mutex::new(exr),
            port: Arc::clone(&port_cell),
            measuring: AtomicBool::new(false),
        });
        let handler = {
            let shared = Arc::clone(&shared);
            Arc::new(move |r: &Request| answer(&shared, r))
        };
        let http = http::Server::bind(port, handler)
            .map_err(|source| crate::error::ViewError::Listen { port, source })?;
        let _ = port_cell.set(http.addr().port());
        prepare(&shared, true);
        Ok(Viewer { http, shared })
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.http.addr())
    }

    pub fn addr(&self) -> SocketAddr {
        self.http.addr()
    }

    pub fn shared(&self) -> &Arc<Shared> {
        &self.shared
    }

    /// Stops accepting requests, lets the ones in progress finish (a comp being written
    /// completes) and joins every thread.
    pub fn stop(self) {
        self.http.stop();
    }
}

/// Asks the desktop to open `url` (`xdg-open`, or `open` on macOS); `false` when neither
/// could be started, which is no error: the URL is printed anyway.
pub fn open_browser(url: &str) -> bool {
    ["xdg-open", "open"].iter().any(|cmd| {
        let child = std::process::Command::new(cmd)
            .arg(url)
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn();
        // Reaped when it exits (at once on a headless machine), so no defunct opener
        // lingers beside the server.
        child
            .map(|mut c| std::thread::spawn(move || c.wait()))
            .is_ok()
    })
}

fn json(status: u16, value: &serde_json::Value) -> Response {
    Response {
        status,
        content_type: "application/json",
        body: value.to_string().into_bytes(),
        headers: vec![],
    }
}

fn error(status: u16, message: impl Into<String>) -> Response {
    json(status, &serde_json::json!({ "error": message.into() }))
}

fn text(content_type: &'static str, body: &str) -> Response {
    Response {
        status: 200,
        content_type,
        body: body.as_bytes().to_vec(),
        headers: vec![],
    }
}

fn image(img: HalfImage) -> Response {
    Response {
        status: 200,
        content_type: "application/octet-stream",
        headers: vec![
            ("X-Width", img.width.to_string()),
            ("X-Height", img.height.to_string()),
            ("X-Channels", img.channels.to_string()),
        ],
        body: img.bytes,
    }
}

fn answer(shared: &Arc<Shared>, request: &Request) -> Response {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| route(shared, request)))
        .unwrap_or_else(|_| error(500, "internal error"))
}

fn route(shared: &Arc<Shared>, request: &Request) -> Response {
    let host = request.header("Host").unwrap_or("");
    let port = shared.port.get().copied().unwrap_or(0);
    if host != format!("127.0.0.1:{port}") && host != format!("localhost:{port}") {
        return error(403, format!("unexpected Host '{host}'"));
    }
    let url = request.target.as_str();
    let (path, query) = url.split_once('?').unwrap_or((url, ""));
    let query = parse_query(query);
    let get = |k: &str| query.iter().find(|(n, _)| n == k).map(|(_, v)| v.as_str());
    let number = |k: &str| get(k).and_then(|v| v.parse::<usize>().ok());
    let read = || shared.data.read().unwrap_or_else(|e| e.into_inner());
    match (request.method.as_str(), path) {
        ("GET", "/" | "/index.html") => text("text/html; charset=utf-8", INDEX_HTML),
        ("GET", "/app.js") => text("text/javascript; charset=utf-8", APP_JS),
        ("GET", "/style.css") => text("text/css; charset=utf-8", STYLE_CSS),
        ("GET", "/api/info") => {
            let mut info = read().info();
            prepare(shared, false);
            let comp = shared
                .exr
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .is_some();
            info["comp"] = comp.into();
            json(200, &info)
        }
        ("GET", "/api/image") => {
            let Some(name) = get("name") else {
                return error(400, "expected ?name=AOV");
            };
            let width = number("width").unwrap_or(usize::MAX);
            match read().image(name, width) {
                Some(img) => image(img),
                None => error(404, format!("no AOV or Cryptomatte layer '{name}'")),
            }
        }
        ("GET", "/api/pixel") => match (number("x"), number("y")) {
            (Some(x), Some(y)) => match read().pixel(x, y) {
                Some(v) => json(200, &v),
                None => error(404, format!("pixel ({x}, {y}) is outside the image")),
            },
            _ => error(400, "expected ?x=X&y=Y (whole numbers)"),
        },
        ("GET", "/api/matte") => {
            let (Some(layer), Some(id)) = (get("layer"), get("id")) else {
                return error(400, "expected ?layer=NAME&id=HEX");
            };
            let Ok(id) = u32::from_str_radix(id, 16) else {
                return error(400, format!("id '{id}' is not 8 hex digits"));
            };
            match read().matte(layer, id) {
                Some(img) => image(img),
                None => error(404, format!("no Cryptomatte layer '{layer}'")),
            }
        }
        ("POST", "/api/comp") => comp(shared, request),
        (_, "/api/comp") => error(405, "POST a comp"),
        _ => error(404, format!("nothing at {path}")),
    }
}

/// Measures the partition checks on a thread of their own, once per generation: the page
/// shows them as "not measured yet" meanwhile, and every image request goes on. With
/// `thumbnails` (a file just shown, not a live render), the thread first makes every
/// thumbnail, which the page asks for first: both passes read every AOV, and on two
/// cores the thumbnails would otherwise wait behind the checks.
fn prepare(shared: &Arc<Shared>, thumbnails: bool) {
    let (unmeasured, live) = {
        let data = shared.data.read().unwrap_or_else(|e| e.into_inner());
        (data.unmeasured(), data.live)
    };
    let thumbnails = thumbnails && !live;
    if (unmeasured.is_none() && !thumbnails) || shared.measuring.swap(true, Ordering::SeqCst) {
        return;
    }
    let shared = Arc::clone(shared);
    std::thread::spawn(move || {
        if thumbnails {
            shared
                .data
                .read()
                .unwrap_or_else(|e| e.into_inner())
                .thumbnails();
        }
        let measured = {
            let data = shared.data.read().unwrap_or_else(|e| e.into_inner());
            data.unmeasured().map(|g| (g, data.measure()))
        };
        if let Some((g, checks)) = measured {
            shared.update(|d| d.set_checks(g, checks));
        }
        shared.measuring.store(false, Ordering::SeqCst);
    });
}

/// What the page posts to save a comp.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CompRequest {
    /// `GROUP=GAIN` or `GROUP=R,G,B`, as `lightpath comp --gain` takes them.
    gains: Vec<String>,
    base: Option<String>,
    /// A file name (no folder): the comp is written beside the EXR.
    output: String,
    #[serde(default)]
    exposure: f32,
}

fn comp(shared: &Shared, request: &Request) -> Response {
    let is_json = request
        .header("Content-Type")
        .is_some_and(|t| t.starts_with("application/json"));
    if !is_json {
        return error(415, "post the comp as application/json");
    }
    let req: CompRequest = match serde_json::from_slice(&request.body) {
        Ok(r) => r,
        Err(e) => return error(400, format!("bad comp request: {e}")),
    };
    let Some(exr) = shared.exr.lock().unwrap_or_else(|e| e.into_inner()).clone() else {
        return error(409, "the render has not written its EXR yet");
    };
    let plain_name = Path::new(&req.output)
        .file_name()
        .is_some_and(|n| n == req.output.as_str());
    if !plain_name || !req.output.ends_with(".exr") || req.output.starts_with('.') {
        return error(
            400,
            format!(
                "output '{}': expected a file name ending in .exr, no folder",
                req.output
            ),
        );
    }
    let output = exr.with_file_name(&req.output);
    if output == exr {
        return error(400, "the comp would overwrite the EXR it reads");
    }
    let job = CompJob {
        exr: exr.clone(),
        expression: None,
        gains: req.gains,
        base: req
            .base
            .unwrap_or_else(|| crate::aov::naming::BEAUTY.to_string()),
        output,
        exposure: req.exposure,
    };
    match crate::post::comp::run(&job) {
        Ok(png) => json(
            200,
            &serde_json::json!({
                "output": job.output.display().to_string(),
                "png": png.display().to_string(),
                "command": command_line(&job),
            }),
        ),
        Err(e) => error(400, e),
    }
}

/// The `lightpath comp` command that writes the same file as `job`.
pub fn command_line(job: &CompJob) -> String {
    let mut args = vec![
        "lightpath".to_string(),
        "comp".into(),
        job.exr.display().to_string(),
        "-o".into(),
        job.output.display().to_string(),
    ];
    if job.base != crate::aov::naming::BEAUTY {
        args.extend(["--base".into(), job.base.clone()]);
    }
    for g in &job.gains {
        args.extend(["--gain".into(), g.clone()]);
    }
    if job.exposure != 0.0 {
        args.extend(["--exposure".into(), job.exposure.to_string()]);
    }
    args.iter()
        .map(|a| shell_quote(a))
        .collect::<Vec<_>>()
        .join(" ")
}

/// `arg` as a POSIX shell word.
fn shell_quote(arg: &str) -> String {
    let plain = !arg.is_empty()
        && arg
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"_-.,/=:+@%".contains(&b));
    if plain {
        arg.to_string()
    } else {
        format!("'{}'", arg.replace('\'', r"'\''"))
    }
}

/// `a=1&b=x%20y` → pairs, percent-decoded (`+` is a space).
fn parse_query(q: &str) -> Vec<(String, String)> {
    q.split('&')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (k, v) = p.split_once('=').unwrap_or((p, ""));
            (percent_decode(k), percent_decode(v))
        })
        .collect()
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match b[i] {
            b'%' if i + 2 < b.len() => match (hex(b[i + 1]), hex(b[i + 2])) {
                (Some(h), Some(l)) => {
                    out.push((h * 16 + l) as u8);
                    i += 3;
                    continue;
                }
                _ => out.push(b'%'),
            },
            b'+' => out.push(b' '),
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_decode_and_words_quote() {
        assert_eq!(
            parse_query("name=beauty_key&x=%41b+c&bad=%zz&end=%4"),
            vec![
                ("name".into(), "beauty_key".into()),
                ("x".into(), "Ab c".into()),
                ("bad".into(), "%zz".into()),
                ("end".into(), "%4".into()),
            ]
        );
        assert_eq!(shell_quote("key=0.5"), "key=0.5");
        assert_eq!(shell_quote("my shot.exr"), "'my shot.exr'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
    }
}
