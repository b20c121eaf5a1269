//! Helpers of the editor's tests: a small scene in a temporary folder, a server on a runtime of
//! its own, and a plain HTTP/1.1 client (std only), so the tests see the server as a browser does.

#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::time::Duration;

use photonix::editor::{BackendChoice, ServeOptions, Server};

/// A scene with comments in odd places, every kind of entry the edits touch, and a tiny image.
pub const SCENE: &str = r#"# A test scene for the editor. This comment must survive every save.
[camera]
position = [0, 1, 4]   # the eye
look_at = [0, 0.5, 0]
fov = 45
resolution = [24, 16]

[render]
spp = 1
passes = 2

[photons]
count = 2000
caustic_count = 1000
gather_rays = 1

# Materials
[materials.white]
type = "diffuse"
reflectance = [0.7, 0.7, 0.7]   # grey

[materials.red]
type = "diffuse"
reflectance = [0.7, 0.1, 0.1]

[materials.glass]
type = "dielectric"
ior = 1.5

[[shapes]]
name = "floor"   # the ground
type = "quad"
material = "white"
vertices = [[-2, 0, -2], [-2, 0, 2], [2, 0, 2], [2, 0, -2]]

[[shapes]]
name = "ball"
type = "sphere"
material = "red"
center = [0, 0.5, 0]
radius = 0.5

# A block, turned.
[[shapes]]
name = "block"
type = "box"
material = "white"
min = [-0.25, 0, -0.25]
max = [0.25, 0.5, 0.25]
[shapes.transform]
rotate = [0, 30, 0]
translate = [1, 0, 0]

[[lights]]
name = "lamp"
type = "area"
shape = "quad"
vertices = [[-0.5, 2, -0.5], [0.5, 2, -0.5], [0.5, 2, 0.5], [-0.5, 2, 0.5]]
radiance = 5

[[lights]]
name = "fill"
type = "point"
position = [2, 2, 2]
intensity = 1
"#;

/// Appended to `SCENE`: an object (a post: a white box with a red ball on top) placed once, on a
/// 3 x 1 x 2 grid in glass, and twice through another object turned a quarter about y; and a
/// CSG box with a ball taken out of its corner (the cut red).
pub const INSTANCES: &str = r#"
[[objects.post.shapes]]
type = "box"
material = "white"
min = [-0.1, 0, -0.1]
max = [0.1, 1, 0.1]

[[objects.post.shapes]]
type = "sphere"
material = "red"
center = [0, 1.1, 0]
radius = 0.1

[objects.pair]
instances = [
  { object = "post", transform = { translate = [0.3, 0, 0] } },
  { object = "post", transform = { translate = [-0.3, 0, 0] } },
]

[[instances]]
name = "single"
object = "post"
transform = { translate = [3, 0, 0] }

[[instances]]
name = "fence"
object = "post"
material = "glass"
transform = { translate = [-1.5, 0, -1.5] }
count = [3, 1, 2]
spacing = [0.5, 0, 1]

[[instances]]
name = "pairs"
object = "pair"
transform = { rotate = [0, 90, 0], translate = [0, 0, 1.5] }

[[shapes]]
name = "cut box"
type = "csg"
operation = "difference"
material = "white"
children = [
  { type = "box", min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5] },
  { type = "sphere", center = [0.5, 1, 0.5], radius = 0.6, material = "red" },
]
"#;

pub struct Fixture {
    pub dir: tempfile::TempDir,
    pub scene: PathBuf,
    pub runtime: tokio::runtime::Runtime,
    pub server: Option<Server>,
}

impl Fixture {
    pub fn new() -> Fixture {
        Fixture::with(BackendChoice::Cpu, |_| {})
    }

    /// A fixture whose scene is `SCENE` followed by `extra`.
    pub fn with_text(extra: &str) -> Fixture {
        Fixture::with(BackendChoice::Cpu, |o| {
            std::fs::write(&o.scene, format!("{SCENE}{extra}")).expect("write the scene");
        })
    }

    /// A fixture whose options `adjust` may change before the server starts.
    pub fn with(backend: BackendChoice, adjust: impl FnOnce(&mut ServeOptions)) -> Fixture {
        let dir = tempfile::tempdir().expect("temporary folder");
        let scene = dir.path().join("scene.toml");
        std::fs::write(&scene, SCENE).expect("write the scene");
        let runtime = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
        let mut options = ServeOptions::new(scene.clone());
        options.backend = backend;
        options.preview_size = 32;
        adjust(&mut options);
        let server = runtime.block_on(Server::start(options)).expect("server starts");
        Fixture { dir, scene, runtime, server: Some(server) }
    }

    pub fn server(&self) -> &Server {
        self.server.as_ref().expect("running")
    }

    pub fn addr(&self) -> SocketAddr {
        self.server().addr
    }

    pub fn token(&self) -> String {
        self.server().token.clone()
    }

    /// A request with the token in the query.
    pub fn call(&self, method: &str, path: &str, body: &[u8]) -> Response {
        let sep = if path.contains('?') { '&' } else { '?' };
        http(self.addr(), method, &format!("{path}{sep}token={}", self.token()), &[], body)
    }

    pub fn edit(&self, command: serde_json::Value) -> Response {
        self.call("POST", "/api/edit", command.to_string().as_bytes())
    }

    pub fn scene_json(&self) -> serde_json::Value {
        let r = self.call("GET", "/api/scene", b"");
        assert_eq!(r.status, 200, "{}", r.text());
        r.json()
    }

    pub fn text(&self) -> String {
        self.server().scene_text()
    }
}

impl Drop for Fixture {
    fn drop(&mut self) {
        if let Some(server) = self.server.take() {
            self.runtime.block_on(server.shutdown());
        }
    }
}

pub struct Response {
    pub status: u16,
    pub headers: Vec<(String, String)>,
    pub body: Vec<u8>,
}

impl Response {
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body).unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.text()))
    }
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)).map(|(_, v)| v.as_str())
    }
}

/// One HTTP/1.1 request on a new connection; `path` is sent as given (no normalisation).
pub fn http(addr: SocketAddr, method: &str, path: &str, headers: &[(&str, &str)], body: &[u8]) -> Response {
    let mut stream = TcpStream::connect(addr).expect("connect");
    stream.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    let mut request =
        format!("{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Length: {}\r\n", body.len());
    for (name, value) in headers {
        request += &format!("{name}: {value}\r\n");
    }
    request += "\r\n";
    stream.write_all(request.as_bytes()).expect("send");
    // A server may answer (413) and close before reading a large body.
    let _ = stream.write_all(body);
    // Read until the body is complete (by Content-Length or the last chunk): a server may keep
    // the connection open whatever `Connection: close` asked.
    let mut raw = Vec::new();
    let mut buf = [0u8; 65536];
    loop {
        if response_complete(&raw) {
            break;
        }
        match stream.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => raw.extend_from_slice(&buf[..n]),
        }
    }
    parse_response(&raw)
}

fn response_complete(raw: &[u8]) -> bool {
    let Some(end) = raw.windows(4).position(|w| w == b"\r\n\r\n") else { return false };
    let head = String::from_utf8_lossy(&raw[..end]).to_ascii_lowercase();
    let body = &raw[end + 4..];
    if let Some(length) = head.lines().find_map(|l| l.strip_prefix("content-length:")) {
        return length.trim().parse::<usize>().is_ok_and(|n| body.len() >= n);
    }
    if head.contains("transfer-encoding: chunked") {
        return body.ends_with(b"0\r\n\r\n");
    }
    false
}

fn parse_response(raw: &[u8]) -> Response {
    let end = raw
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .unwrap_or_else(|| panic!("no HTTP header in {:?}", String::from_utf8_lossy(raw)));
    let head = String::from_utf8_lossy(&raw[..end]).into_owned();
    let mut lines = head.split("\r\n");
    let status: u16 = lines.next().and_then(|l| l.split(' ').nth(1)).and_then(|s| s.parse().ok()).expect("status line");
    let headers: Vec<(String, String)> =
        lines.filter_map(|l| l.split_once(':').map(|(n, v)| (n.trim().to_string(), v.trim().to_string()))).collect();
    let mut body = raw[end + 4..].to_vec();
    let chunked = headers.iter().any(|(n, v)| n.eq_ignore_ascii_case("transfer-encoding") && v.contains("chunked"));
    if chunked {
        let mut out = Vec::new();
        let mut rest = &body[..];
        loop {
            let line_end = rest.windows(2).position(|w| w == b"\r\n").expect("chunk size line");
            let size =
                usize::from_str_radix(String::from_utf8_lossy(&rest[..line_end]).trim(), 16).expect("chunk size");
            if size == 0 {
                break;
            }
            out.extend_from_slice(&rest[line_end + 2..line_end + 2 + size]);
            rest = &rest[line_end + 2 + size + 2..];
        }
        body = out;
    }
    Response { status, headers, body }
}

/// Parses a scene text as the renderer would.
pub fn parse(text: &str, path: &Path) -> photonix::scene::Scene {
    photonix::scene::parse_scene(text, path).unwrap_or_else(|e| panic!("{e}\n{text}"))
}
