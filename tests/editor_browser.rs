//! The editor in a real browser: headless Chromium (Debian's `chromium` and `chromium-driver`,
//! which ci/setup installs) driven over WebDriver. It waits for the first rendered frame, clicks
//! the ball in the viewport and checks the properties panel, moves the ball by a typed value and
//! checks the server's scene, deletes it, undoes, saves and checks the file. Screenshots of each
//! step go to target/editor-browser/ (kept as artifacts).

mod editor_support;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use editor_support::{http, Fixture};
use serde_json::{json, Value};

const CHROMIUM: &str = "/usr/bin/chromium";
const CHROMEDRIVER: &str = "/usr/bin/chromedriver";

/// chromedriver, killed on drop.
struct Driver {
    child: Child,
    addr: SocketAddr,
    session: String,
    shots: PathBuf,
    _profile: tempfile::TempDir,
}

impl Driver {
    fn start() -> Driver {
        for path in [CHROMIUM, CHROMEDRIVER] {
            assert!(
                std::path::Path::new(path).exists(),
                "{path} is missing; run ci/setup (it installs chromium and chromium-driver)"
            );
        }
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let child = Command::new(CHROMEDRIVER)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start chromedriver");
        let addr: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
        let start = Instant::now();
        while std::net::TcpStream::connect(addr).is_err() {
            assert!(start.elapsed() < Duration::from_secs(20), "chromedriver did not start");
            std::thread::sleep(Duration::from_millis(50));
        }
        let profile = tempfile::tempdir().unwrap();
        let args = [
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--window-size=1280,800",
            &format!("--user-data-dir={}", profile.path().display()),
        ];
        let caps = json!({ "capabilities": { "alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": { "binary": CHROMIUM, "args": args },
        } } });
        let mut driver = Driver { child, addr, session: String::new(), shots: shots_dir(), _profile: profile };
        let reply = driver.call("POST", "/session", caps);
        driver.session = reply["sessionId"].as_str().unwrap_or_else(|| panic!("no session: {reply}")).to_string();
        driver
    }

    fn call(&self, method: &str, path: &str, body: Value) -> Value {
        let body = if body.is_null() { Vec::new() } else { body.to_string().into_bytes() };
        let r = http(self.addr, method, path, &[("Content-Type", "application/json")], &body);
        let value: Value =
            serde_json::from_slice(&r.body).unwrap_or_else(|_| panic!("{} {path}: {}", r.status, r.text()));
        assert_eq!(r.status, 200, "{method} {path}: {value}");
        value["value"].clone()
    }

    fn session(&self, method: &str, path: &str, body: Value) -> Value {
        self.call(method, &format!("/session/{}{path}", self.session), body)
    }

    fn script(&self, script: &str) -> Value {
        self.session("POST", "/execute/sync", json!({ "script": script, "args": [] }))
    }

    /// Polls `script` (which returns a value) until `done` accepts it.
    fn wait_for(&self, what: &str, script: &str, done: impl Fn(&Value) -> bool) -> Value {
        let start = Instant::now();
        loop {
            let v = self.script(script);
            if done(&v) {
                return v;
            }
            assert!(start.elapsed() < Duration::from_secs(90), "timed out waiting for {what}: last {v}");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn element(&self, css: &str) -> String {
        let v = self.session("POST", "/element", json!({ "using": "css selector", "value": css }));
        v.as_object().and_then(|o| o.values().next()).and_then(|v| v.as_str()).expect("element id").to_string()
    }

    fn click(&self, css: &str) {
        let id = self.element(css);
        self.session("POST", &format!("/element/{id}/click"), json!({}));
    }

    fn type_into(&self, css: &str, text: &str) {
        let id = self.element(css);
        self.session("POST", &format!("/element/{id}/clear"), json!({}));
        self.session("POST", &format!("/element/{id}/value"), json!({ "text": text }));
    }

    fn screenshot(&self, name: &str) {
        let v = self.session("GET", "/screenshot", Value::Null);
        let bytes = base64_decode(v.as_str().expect("base64 PNG"));
        std::fs::write(self.shots.join(name), bytes).unwrap();
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        if !self.session.is_empty() {
            let _ = http(self.addr, "DELETE", &format!("/session/{}", self.session), &[], b"");
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn shots_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/editor-browser");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => (c - b'A') as u32,
            b'a'..=b'z' => (c - b'a' + 26) as u32,
            b'0'..=b'9' => (c - b'0' + 52) as u32,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let clean: Vec<u8> = text.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    let mut out = Vec::new();
    for chunk in clean.chunks(4) {
        let n = chunk.iter().take_while(|&&c| c != b'=').count();
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().take(n).enumerate() {
            acc |= value(c) << (18 - 6 * i);
        }
        out.extend_from_slice(&acc.to_be_bytes()[1..n.max(1)]);
    }
    out
}

/// Waits until the server's scene text satisfies `done`.
fn wait_text(f: &Fixture, what: &str, done: impl Fn(&str) -> bool) -> String {
    let start = Instant::now();
    loop {
        let text = f.text();
        if done(&text) {
            return text;
        }
        assert!(start.elapsed() < Duration::from_secs(30), "timed out waiting for {what}:\n{text}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn browser_selects_moves_deletes_undoes_and_saves() {
    let f = Fixture::with(photonix::editor::BackendChoice::Cpu, |o| o.preview_size = 96);
    let driver = Driver::start();
    driver.session("POST", "/url", json!({ "url": f.server().url() }));

    // The first rendered frame
    driver.wait_for("the first rendered frame", "return Number(document.body.dataset.frames || 0)", |v| {
        v.as_u64().unwrap_or(0) >= 1
    });
    // The token left the address bar (the cookie carries it).
    let url = driver.session("GET", "/url", Value::Null);
    assert!(!url.as_str().unwrap().contains("token"), "{url}");
    driver.screenshot("01-first-frame.png");

    // Click the ball in the viewport (solid shading, so the click lands on drawn geometry)
    driver.click("#shading");
    let point = driver.script(
        "const e = window.photonixEditor, v = e.viewport, c = v.canvas.getBoundingClientRect();
         const p = new v.perspective.position.constructor(0, 0.5, 0).project(v.perspective);
         return [(p.x * 0.5 + 0.5) * c.width - c.width / 2, (-p.y * 0.5 + 0.5) * c.height - c.height / 2];",
    );
    // The scene's camera looks at the ball's centre, so it is under the canvas's centre, where
    // WebDriver's element click presses the mouse.
    let (dx, dy) = (point[0].as_f64().unwrap(), point[1].as_f64().unwrap());
    assert!(dx.abs() < 2.0 && dy.abs() < 2.0, "the ball projects to ({dx}, {dy}) from the centre");
    driver.click("#canvas");
    driver.wait_for("the ball to be selected", "return document.body.dataset.selection", |v| v == "shape:1");
    let name = driver.script("return document.getElementById('obj-name').value");
    assert_eq!(name, "ball");
    let radius = driver.script("return document.getElementById('obj-radius').value");
    assert_eq!(radius, "0.5");
    let colour = driver.script("return document.getElementById('mat-reflectance-0').value");
    assert_eq!(colour, "0.7");
    assert!(driver.script("return document.querySelector('#tree-shape-1').classList.contains('selected')") == true);
    driver.screenshot("02-selected.png");

    // Move it by a typed value; the server's scene changes
    driver.type_into("#tf-translate-0", "0.75\n");
    let text = wait_text(&f, "the move", |t| t.contains("transform = { translate = [0.75, 0, 0] }"));
    assert!(text.contains("name = \"ball\""));
    driver.wait_for("the moved ball in the panel", "return document.getElementById('tf-translate-0')?.value", |v| {
        v == "0.75"
    });
    let frames = driver.script("return Number(document.body.dataset.frames)").as_u64().unwrap();
    driver.click("#shading");
    driver.wait_for("a frame after the move", "return Number(document.body.dataset.frames)", |v| {
        v.as_u64() > Some(frames)
    });
    driver.screenshot("03-moved.png");

    // Delete, then undo
    driver.click("#delete");
    wait_text(&f, "the deletion", |t| !t.contains("name = \"ball\""));
    driver.wait_for("the tree without the ball", "return document.querySelectorAll('[id^=tree-shape-]').length", |v| {
        v == 2
    });
    driver.screenshot("04-deleted.png");
    driver.click("#undo");
    let text = wait_text(&f, "the undo", |t| t.contains("name = \"ball\""));
    assert!(text.contains("translate = [0.75, 0, 0]"), "{text}");
    driver
        .wait_for("the tree with the ball", "return document.querySelectorAll('[id^=tree-shape-]').length", |v| v == 3);
    driver.screenshot("05-undone.png");

    // Save: the file on disk is the edited scene, comments and all
    driver.click("#save");
    let start = Instant::now();
    let saved = loop {
        let saved = std::fs::read_to_string(&f.scene).unwrap();
        if saved.contains("translate = [0.75, 0, 0]") {
            break saved;
        }
        assert!(start.elapsed() < Duration::from_secs(30), "the save did not reach the file:\n{saved}");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(saved, f.text());
    assert!(saved.contains("# A test scene for the editor."));
    let scene = photonix::scene::load_scene(&f.scene).unwrap();
    let ball = scene.spheres().next().unwrap().0;
    assert!((ball.center.x - 0.75).abs() < 1e-6, "{}", ball.center);
    driver
        .wait_for("the saved state", "return document.getElementById('file-name').textContent", |v| v == "scene.toml");
    driver.screenshot("06-saved.png");
    // No error was shown on the way.
    let error = driver.script("return document.body.dataset.lastError || ''");
    assert_eq!(error, "", "the page showed an error");
}
