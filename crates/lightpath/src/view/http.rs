//! The viewer's HTTP/1.1 server: one thread per connection, keep-alive with an idle
//! timeout, request heads parsed by `httparse`.
//!
//! Why not `tiny_http`: its connection pool can leave a new connection queued behind
//! kept-alive ones (a task spawned while the only idle thread is waking is queued, and
//! that thread then serves a keep-alive connection for as long as the browser keeps it).
//! A page opening six connections at once hung on two of them about half the time. A
//! browser opens few connections to one host, so a thread each is cheap and never starves.

use std::io::{BufWriter, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// A connection idle this long is closed.
const IDLE: Duration = Duration::from_secs(30);
/// The largest request head (request line and headers) accepted.
const MAX_HEAD: usize = 16 << 10;
/// The largest request body accepted.
const MAX_BODY: usize = 64 << 10;
/// Connections served at once; more wait in the listener's backlog.
const MAX_CONNECTIONS: usize = 64;

/// A request as the handler sees it.
pub struct Request {
    pub method: String,
    /// The request target: path and query.
    pub target: String,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

impl Request {
    /// A header's value (names compare without case).
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// A response: status, content type, body and extra headers.
pub struct Response {
    pub status: u16,
    pub content_type: &'static str,
    pub headers: Vec<(&'static str, String)>,
    pub body: Vec<u8>,
}

type Handler = dyn Fn(&Request) -> Response + Send + Sync;

/// Open connections, so that stopping can end them.
struct Connections {
    streams: Vec<(u64, TcpStream)>,
    threads: Vec<JoinHandle<()>>,
    next: u64,
}

/// A running server.
pub struct Server {
    addr: SocketAddr,
    stopping: Arc<AtomicBool>,
    connections: Arc<Mutex<Connections>>,
    accept: Option<JoinHandle<()>>,
}

impl Server {
    /// Listens on 127.0.0.1:`port` (0: a free port) and answers with `handler`.
    pub fn bind(port: u16, handler: Arc<Handler>) -> std::io::Result<Server> {
        let listener = TcpListener::bind(("127.0.0.1", port))?;
        let addr = listener.local_addr()?;
        let stopping = Arc::new(AtomicBool::new(false));
        let connections = Arc::new(Mutex::new(Connections {
            streams: Vec::new(),
            threads: Vec::new(),
            next: 0,
        }));
        let accept = {
            let (stopping, connections) = (Arc::clone(&stopping), Arc::clone(&connections));
            std::thread::spawn(move || accept_loop(listener, handler, stopping, connections))
        };
        Ok(Server {
            addr,
            stopping,
            connections,
            accept: Some(accept),
        })
    }

    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Stops accepting, lets requests being answered finish, closes every connection and
    /// joins every thread.
    pub fn stop(mut self) {
        self.stopping.store(true, Ordering::SeqCst);
        // Wake the accept loop with a connection of our own.
        let _ = TcpStream::connect(self.addr);
        if let Some(a) = self.accept.take() {
            let _ = a.join();
        }
        let threads = {
            let mut c = lock(&self.connections);
            for (_, s) in &c.streams {
                // A thread reading the next request sees the end; one answering finishes.
                let _ = s.shutdown(Shutdown::Read);
            }
            std::mem::take(&mut c.threads)
        };
        for t in threads {
            let _ = t.join();
        }
    }
}

fn lock(c: &Mutex<Connections>) -> std::sync::MutexGuard<'_, Connections> {
    c.lock().unwrap_or_else(|e| e.into_inner())
}

fn accept_loop(
    listener: TcpListener,
    handler: Arc<Handler>,
    stopping: Arc<AtomicBool>,
    connections: Arc<Mutex<Connections>>,
) {
    for stream in listener.incoming() {
        if stopping.load(Ordering::SeqCst) {
            break;
        }
        let Ok(stream) = stream else { continue };
        let mut c = lock(&connections);
        c.threads.retain(|t| !t.is_finished());
        if c.threads.len() >= MAX_CONNECTIONS {
            continue; // dropped: the client sees the connection close
        }
        let id = c.next;
        c.next += 1;
        if let Ok(clone) = stream.try_clone() {
            c.streams.push((id, clone));
        }
        let (handler, conns) = (Arc::clone(&handler), Arc::clone(&connections));
        let stop = Arc::clone(&stopping);
        c.threads.push(std::thread::spawn(move || {
            serve(stream, &*handler, &stop);
            lock(&conns).streams.retain(|(i, _)| *i != id);
        }));
    }
}

/// Answers the requests of one connection until it closes, idles or asks to close.
fn serve(mut stream: TcpStream, handler: &Handler, stopping: &AtomicBool) {
    let _ = stream.set_read_timeout(Some(IDLE));
    let _ = stream.set_write_timeout(Some(IDLE));
    let _ = stream.set_nodelay(true);
    let mut buf = Vec::new();
    loop {
        let (request, close) = match read_request(&mut stream, &mut buf) {
            Ok(Some(r)) => r,
            Ok(None) => return,
            Err(response) => {
                let _ = write_response(&mut stream, &response, true);
                return;
            }
        };
        let response = handler(&request);
        let close = close || stopping.load(Ordering::SeqCst);
        if write_response(&mut stream, &response, close).is_err() || close {
            let _ = stream.shutdown(Shutdown::Both);
            return;
        }
    }
}

fn error(status: u16, message: &str) -> Response {
    Response {
        status,
        content_type: "application/json",
        headers: vec![],
        body: serde_json::json!({ "error": message })
            .to_string()
            .into_bytes(),
    }
}

/// Reads one request; `Ok(None)` when the client closed (or idled) between requests,
/// `Err` with the response to send before closing when the request is malformed. The
/// flag says whether the client asked to close after this request.
fn read_request(
    stream: &mut TcpStream,
    buf: &mut Vec<u8>,
) -> Result<Option<(Request, bool)>, Response> {
    let mut chunk = [0u8; 8192];
    loop {
        let mut headers = [httparse::EMPTY_HEADER; 64];
        let mut head = httparse::Request::new(&mut headers);
        match head.parse(buf) {
            Ok(httparse::Status::Complete(len)) => {
                let headers: Vec<(String, String)> = head
                    .headers
                    .iter()
                    .map(|h| {
                        (
                            h.name.to_string(),
                            String::from_utf8_lossy(h.value).trim().to_string(),
                        )
                    })
                    .collect();
                let mut request = Request {
                    method: head.method.unwrap_or("").to_string(),
                    target: head.path.unwrap_or("").to_string(),
                    headers,
                    body: Vec::new(),
                };
                let version = head.version.unwrap_or(1);
                let connection = request.header("Connection").map(str::to_ascii_lowercase);
                let close = match connection.as_deref() {
                    Some(c) if c.contains("close") => true,
                    Some(c) if c.contains("keep-alive") => false,
                    _ => version == 0,
                };
                if request.header("Transfer-Encoding").is_some() {
                    return Err(error(411, "send the body with a Content-Length"));
                }
                let body_len = match request.header("Content-Length") {
                    None => 0,
                    Some(v) => match v.parse::<usize>() {
                        Ok(n) if n <= MAX_BODY => n,
                        Ok(_) => return Err(error(413, "the body is too large")),
                        Err(_) => return Err(error(400, "bad Content-Length")),
                    },
                };
                while buf.len() < len + body_len {
                    match stream.read(&mut chunk) {
                        Ok(0) | Err(_) => return Err(error(400, "the body ended early")),
                        Ok(n) => buf.extend_from_slice(&chunk[..n]),
                    }
                }
                request.body = buf[len..len + body_len].to_vec();
                buf.drain(..len + body_len);
                return Ok(Some((request, close)));
            }
            Ok(httparse::Status::Partial) if buf.len() > MAX_HEAD => {
                return Err(error(431, "the request head is too large"));
            }
            Ok(httparse::Status::Partial) => match stream.read(&mut chunk) {
                Ok(0) | Err(_) if buf.is_empty() => return Ok(None),
                Ok(0) | Err(_) => return Err(error(400, "the request ended early")),
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            },
            Err(e) => return Err(error(400, &format!("malformed request: {e}"))),
        }
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        409 => "Conflict",
        411 => "Length Required",
        413 => "Payload Too Large",
        415 => "Unsupported Media Type",
        431 => "Request Header Fields Too Large",
        _ => "Internal Server Error",
    }
}

fn write_response(stream: &mut TcpStream, r: &Response, close: bool) -> std::io::Result<()> {
    let mut out = BufWriter::with_capacity(64 << 10, stream);
    write!(
        out,
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nCache-Control: no-store\r\n\
         X-Content-Type-Options: nosniff\r\nConnection: {}\r\n",
        r.status,
        reason(r.status),
        r.content_type,
        r.body.len(),
        if close { "close" } else { "keep-alive" }
    )?;
    for (k, v) in &r.headers {
        write!(out, "{k}: {v}\r\n")?;
    }
    out.write_all(b"\r\n")?;
    out.write_all(&r.body)?;
    out.flush()
}
