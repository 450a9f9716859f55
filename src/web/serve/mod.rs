//! `sdfc serve`: the page `sdfc export-web` writes, served from memory on loopback and
//! rebuilt when the scene or its textures change. The page listens to `/events`
//! (server-sent events): a `scene` event for each good build, which it swaps in keeping
//! its camera, and a `diagnostics` event while the file does not build, which it shows
//! over the last good picture.
//!
//! What is served, and nothing else:
//!
//! - `/` and the page's files (`index.html`, `sdfc.js`, and the last good build's
//!   `scene.wgsl`, `manifest.json`, `web.json`, `textures/I/L.png`), also under
//!   `/gen/N/` for the build of generation N while it is the last good one, so that
//!   a page never mixes two builds;
//! - `/events`;
//! - files of the scene's own folder, resolved by [`crate::access::Access`] (no `..`,
//!   no hidden names, no symbolic link out of the folder, the same 404 whether or not
//!   a refused file exists).
//!
//! The server is std's TCP with a thread per connection, bounded
//! ([`MAX_CONNECTIONS`], [`http::MAX_HEAD_BYTES`], [`HEAD_TIMEOUT`]); GET and HEAD
//! only. On loopback it answers only requests whose `Host` names loopback, so a page
//! of another site cannot reach it through DNS rebinding.

pub mod http;
pub mod site;
pub mod watch;

use crate::access::Access;
use http::Request;
use site::Shared;
use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// The most connections served at once (each open page holds one for its events); one
/// more is answered 503 and closed.
pub const MAX_CONNECTIONS: usize = 64;
/// How long a connection may take to send its request head.
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(10);
/// How long file events are gathered before a rebuild (an editor's save is often a
/// few events).
pub const DEBOUNCE: Duration = Duration::from_millis(100);
/// How often an idle event stream is sent a comment (to notice a closed page).
const KEEPALIVE: Duration = Duration::from_secs(15);

/// What to serve, and where.
pub struct Options {
    /// The scene and how it is built.
    pub source: site::Source,
    /// The address to listen on (loopback unless asked otherwise).
    pub addr: SocketAddr,
}

/// Why the server did not start.
#[derive(Debug)]
pub enum ServeError {
    /// The address cannot be listened on (the port is in use, or the address is not
    /// this machine's).
    Bind(SocketAddr, std::io::Error),
    /// The scene file cannot be read at all.
    Scene(String),
}

impl std::fmt::Display for ServeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ServeError::Bind(addr, e) => write!(f, "cannot listen on {addr}: {e}"),
            ServeError::Scene(e) => f.write_str(e),
        }
    }
}

/// What a connection needs to answer.
struct Server {
    shared: Arc<Shared>,
    /// The scene's folder, and nothing else.
    folder: Access,
    /// The `Host` values accepted (None: any, when not on loopback).
    hosts: Option<Vec<String>>,
    title: String,
    connections: AtomicUsize,
}

/// Builds the scene, listens, says where on standard error and serves until the
/// process ends (Ctrl-C). Each rebuild's report goes to standard error too.
pub fn run(options: Options) -> Result<(), ServeError> {
    let source = options.source;
    std::fs::metadata(&source.scene)
        .map_err(|e| ServeError::Scene(format!("cannot read {}: {e}", source.scene.display())))?;
    let listener =
        TcpListener::bind(options.addr).map_err(|e| ServeError::Bind(options.addr, e))?;
    let addr = listener
        .local_addr()
        .map_err(|e| ServeError::Bind(options.addr, e))?;
    let folder = Access::new(source.access.base.as_deref());
    let shared = Arc::new(Shared::default());
    let server = Arc::new(Server {
        shared: shared.clone(),
        folder,
        hosts: addr.ip().is_loopback().then(|| loopback_hosts(addr)),
        title: site::title(&source.scene),
        connections: AtomicUsize::new(0),
    });
    let name = source.scene.display().to_string();
    let first = rebuild(&source, &shared, &name);
    let (tx, rx) = std::sync::mpsc::channel();
    match watch::Watch::new(tx) {
        Ok(mut w) => {
            for problem in w.set(&first) {
                eprintln!("warning: {problem}");
            }
            std::thread::spawn(move || builder(source, shared, w, rx, name));
        }
        Err(e) => eprintln!("warning: no reload on change: {e}"),
    }
    let shown = match addr.ip() {
        IpAddr::V6(ip) => format!("[{ip}]:{}", addr.port()),
        IpAddr::V4(ip) => format!("{ip}:{}", addr.port()),
    };
    eprintln!("serving {} at http://{shown}/ (Ctrl-C stops)", server.title);
    for stream in listener.incoming() {
        let Ok(stream) = stream else {
            // Out of file descriptors, say: wait a little rather than spin.
            std::thread::sleep(Duration::from_millis(50));
            continue;
        };
        if server.connections.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
            server.connections.fetch_sub(1, Ordering::SeqCst);
            let mut stream = stream;
            let _ = http::respond(
                &mut stream,
                "503 Service Unavailable",
                "text/plain; charset=utf-8",
                b"too many connections\n",
                false,
                "",
            );
            continue;
        }
        let server = server.clone();
        std::thread::spawn(move || {
            server.answer(stream);
            server.connections.fetch_sub(1, Ordering::SeqCst);
        });
    }
    Ok(())
}

fn loopback_hosts(addr: SocketAddr) -> Vec<String> {
    let port = addr.port();
    let mut hosts = vec![
        format!("127.0.0.1:{port}"),
        format!("localhost:{port}"),
        format!("[::1]:{port}"),
    ];
    if let IpAddr::V4(ip) = addr.ip() {
        hosts.push(format!("{ip}:{port}"));
    }
    hosts
}

/// Builds the scene, publishes the outcome, reports it on standard error; the files
/// to watch (the scene and the textures it resolved).
fn rebuild(source: &site::Source, shared: &Shared, name: &str) -> Vec<PathBuf> {
    let started = std::time::Instant::now();
    let outcome = site::build(source);
    let mut watch = vec![source.scene.clone()];
    match &outcome {
        Ok(b) => {
            watch.extend(b.textures.iter().cloned());
            eprint!("{}", b.warnings);
        }
        Err(f) => {
            watch.extend(f.textures.iter().cloned());
            eprint!("{}", f.text);
        }
    }
    let ok = outcome.is_ok();
    if shared.publish(outcome) {
        let generation = shared.files().0;
        if ok {
            eprintln!(
                "built {name} (generation {generation}) in {:.0} ms",
                started.elapsed().as_secs_f64() * 1e3
            );
        } else {
            eprintln!("{name}: not rebuilt; the page keeps generation {generation}");
        }
    }
    watch
}

/// Rebuilds after each burst of changes, [`DEBOUNCE`] after its last event.
fn builder(
    source: site::Source,
    shared: Arc<Shared>,
    mut watch: watch::Watch,
    rx: std::sync::mpsc::Receiver<()>,
    name: String,
) {
    while rx.recv().is_ok() {
        while rx.recv_timeout(DEBOUNCE).is_ok() {}
        let files = rebuild(&source, &shared, &name);
        for problem in watch.set(&files) {
            eprintln!("warning: {problem}");
        }
    }
}

/// The most of a refused request's rest that [`linger`] reads, and for how long.
const LINGER_BYTES: usize = 1 << 20;
const LINGER_TIME: std::time::Duration = std::time::Duration::from_millis(500);

/// A lingering close after a refusal: the answer is sent, the writing side shut, and
/// the rest of the request (at most [`LINGER_BYTES`], for at most [`LINGER_TIME`]) read
/// and dropped. Closing a socket with unread input resets the connection, and a reset
/// can reach the client before it has read the answer (a 431 to an oversized head).
fn linger(stream: &mut TcpStream) {
    use std::io::Read;
    let _ = stream.shutdown(std::net::Shutdown::Write);
    let _ = stream.set_read_timeout(Some(LINGER_TIME));
    let started = std::time::Instant::now();
    let (mut buf, mut read) = ([0u8; 8192], 0);
    while read < LINGER_BYTES && started.elapsed() < LINGER_TIME {
        match stream.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => read += n,
        }
    }
}

impl Server {
    /// Reads one request and answers it; errors writing mean the page went away.
    fn answer(&self, mut stream: TcpStream) {
        let _ = stream.set_read_timeout(Some(HEAD_TIMEOUT));
        let _ = stream.set_write_timeout(Some(HEAD_TIMEOUT));
        let request = match http::read_request(&mut stream) {
            Ok(r) => r,
            Err(why) => {
                let _ = http::refusal(&mut stream, &why);
                linger(&mut stream);
                return;
            }
        };
        if let Some(hosts) = &self.hosts {
            let ok = request
                .host
                .as_ref()
                .is_some_and(|h| hosts.iter().any(|a| a.eq_ignore_ascii_case(h)));
            if !ok {
                let _ = http::respond(
                    &mut stream,
                    "421 Misdirected Request",
                    "text/plain; charset=utf-8",
                    b"this server answers only requests for loopback addresses\n",
                    request.head,
                    "",
                );
                return;
            }
        }
        let _ = self.route(&mut stream, &request);
    }

    fn route(&self, stream: &mut TcpStream, request: &Request) -> std::io::Result<()> {
        let parts: Vec<&str> = request.path.iter().map(String::as_str).collect();
        let head = request.head;
        match parts.as_slice() {
            ["events"] => return self.events(stream, head),
            [] | ["index.html"] => {
                let page = super::index_html(&self.title, true);
                return http::respond(
                    stream,
                    "200 OK",
                    http::content_type("x.html"),
                    &page,
                    head,
                    "",
                );
            }
            ["sdfc.js"] => {
                let js = super::DRIVER_JS.as_bytes();
                return http::respond(stream, "200 OK", http::content_type("x.js"), js, head, "");
            }
            _ => {}
        }
        let (generation, files) = self.shared.files();
        // `/gen/N/…`: the build of generation N, while it is the last good one.
        let (pinned, rest) = match parts.as_slice() {
            ["gen", n, rest @ ..] => (Some(*n), rest),
            _ => (None, parts.as_slice()),
        };
        let key = rest.join("/");
        if let Some(n) = pinned {
            if n.parse::<u64>().ok() != Some(generation) {
                return http::respond(
                    stream,
                    "410 Gone",
                    "text/plain; charset=utf-8",
                    b"a newer build replaced this one\n",
                    head,
                    "",
                );
            }
        }
        if let Some(bytes) = files.as_ref().and_then(|f| f.get(&key)) {
            return http::respond(stream, "200 OK", http::content_type(&key), bytes, head, "");
        }
        if pinned.is_some() {
            return http::not_found(stream, head);
        }
        self.folder_file(stream, &key, head)
    }

    /// A file of the scene's folder, through the same confinement as textures.
    fn folder_file(&self, stream: &mut TcpStream, key: &str, head: bool) -> std::io::Result<()> {
        let bytes = match self.folder.resolve(key) {
            Some(Ok(path)) => std::fs::read(path).ok(),
            _ => None,
        };
        match bytes {
            Some(b) => http::respond(stream, "200 OK", http::content_type(key), &b, head, ""),
            None => http::not_found(stream, head),
        }
    }

    /// The event stream: the current state at once, then each change.
    fn events(&self, stream: &mut TcpStream, head: bool) -> std::io::Result<()> {
        use std::io::Write;
        write!(
            stream,
            "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
             X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n"
        )?;
        if head {
            return stream.flush();
        }
        // Reconnect after a second if the stream breaks.
        stream.write_all(b"retry: 1000\n\n")?;
        stream.flush()?;
        let mut seen = None;
        loop {
            match self.shared.wait(seen, KEEPALIVE) {
                Some((version, event)) => {
                    seen = Some(version);
                    stream.write_all(event.as_bytes())?;
                }
                None => stream.write_all(b": keepalive\n\n")?,
            }
            stream.flush()?;
        }
    }
}
