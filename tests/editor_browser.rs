//! The editor in a real browser: headless Chromium (Debian's `chromium` and `chromium-driver`,
//! which ci/setup installs) driven over WebDriver. It waits for the first rendered frame, clicks
//! the ball in the viewport and checks the properties panel, moves the ball by a typed value and
//! checks the server's scene, drags the move gizmo's X arrow with the mouse (WebDriver pointer
//! actions) and checks the ball moved along x only, undoes that, checks the selection outline
//! in four views, deletes the ball, undoes, saves and checks the file. A second run opens a
//! scene with instances and a CSG object: it selects an instance in the scene tree, checks the
//! properties panel and the outline, moves it by a typed value, picks a texture for a material
//! in the properties panel and checks the server's scene and the saved file. Screenshots of
//! each step go to target/editor-browser/ (kept as artifacts).

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

    /// Performs WebDriver pointer actions of the mouse (`pointerMove` at viewport pixels,
    /// `pointerDown`, `pointerUp`); a button pressed in one call stays down into the next.
    fn pointer(&self, actions: Value) {
        let body = json!({ "actions": [{
            "type": "pointer", "id": "mouse", "parameters": { "pointerType": "mouse" }, "actions": actions,
        }] });
        self.session("POST", "/actions", body);
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

/// Counts the canvas's pixels of the selection outline's colour (0xffa640): in all, then in
/// each quarter (top left, top right, bottom left, bottom right).
const OUTLINE_PIXELS: &str = "const c = document.getElementById('canvas');
    const t = document.createElement('canvas'); t.width = c.width; t.height = c.height;
    const g = t.getContext('2d'); g.drawImage(c, 0, 0);
    const d = g.getImageData(0, 0, t.width, t.height).data;
    const n = [0, 0, 0, 0, 0];
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - 255) < 6 && Math.abs(d[i + 1] - 166) < 6 && Math.abs(d[i + 2] - 64) < 6) {
        const x = (i / 4) % t.width, y = Math.floor(i / 4 / t.width);
        n[0]++; n[1 + (x >= t.width / 2 ? 1 : 0) + (y >= t.height / 2 ? 2 : 0)]++;
      }
    }
    return n;";

fn outline_pixels(driver: &Driver) -> Vec<u64> {
    let v = driver.script(OUTLINE_PIXELS);
    v.as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect()
}

/// The ball's (the second shape's) `transform.translate` in `text`.
fn ball_translate(text: &str) -> [f64; 3] {
    let doc: toml_edit::DocumentMut = text.parse().expect("the server's scene is TOML");
    let ball = &doc["shapes"].as_array_of_tables().expect("[[shapes]]").get(1).expect("the ball")["transform"];
    let t = ball.get("translate").and_then(|t| t.as_array()).unwrap_or_else(|| panic!("no translate: {ball}"));
    let number = |v: &toml_edit::Value| v.as_float().or(v.as_integer().map(|i| i as f64)).expect("a number");
    [0, 1, 2].map(|i| number(t.get(i).expect("three numbers")))
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
    assert!(outline_pixels(&driver).iter().sum::<u64>() < 20, "an outline before any selection");
    driver.click("#canvas");
    driver.wait_for("the ball to be selected", "return document.body.dataset.selection", |v| v == "shape:1");
    // Its silhouette is outlined: a ring of orange pixels around the ball.
    let ring = driver.wait_for("the outline", OUTLINE_PIXELS, |v| v[0].as_u64().unwrap_or(0) > 200);
    assert!(ring[0].as_u64().unwrap() < 20_000, "the outline fills the view: {ring}");
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

    // Drag the move gizmo's X arrow with the mouse; the server's ball moves along x only
    let before_drag = f.text();
    let handle = driver.script(
        "const v = window.photonixEditor.viewport, c = v.canvas.getBoundingClientRect();
         const arrow = v.gizmo._gizmo.picker.translate.children.find((m) => m.name === 'X');
         const V = v.perspective.position.constructor;
         const screen = (p) => { const q = p.project(v.perspective);
           return [c.left + (q.x * 0.5 + 0.5) * c.width, c.top + (-q.y * 0.5 + 0.5) * c.height]; };
         // The arrow's picker runs along x from the gizmo's centre to 0.6 (in the gizmo's frame,
         // which three.js bakes into the pickers' geometry).
         return [screen(arrow.localToWorld(new V(0.45, 0, 0))), screen(arrow.localToWorld(new V(0, 0, 0)))];",
    );
    let at = |i: usize, j: usize| handle[i][j].as_f64().unwrap();
    let (grab, centre) = ([at(0, 0), at(0, 1)], [at(1, 0), at(1, 1)]);
    let along = [grab[0] - centre[0], grab[1] - centre[1]];
    let length = along[0].hypot(along[1]);
    assert!(length > 10.0, "the X arrow is {length} pixels long on screen");
    let unit = [along[0] / length, along[1] / length];
    let point = |distance: f64| -> Value {
        let (x, y) = (grab[0] + unit[0] * distance, grab[1] + unit[1] * distance);
        json!({ "type": "pointerMove", "duration": 0, "origin": "viewport", "x": x.round() as i64, "y": y.round() as i64 })
    };
    driver.pointer(json!([point(0.0), { "type": "pointerDown", "button": 0 }]));
    assert_eq!(driver.script("return window.photonixEditor.viewport.gizmo.axis"), "X", "the press missed the X arrow");
    driver.screenshot("04-gizmo-grabbed.png");
    driver.pointer(Value::Array((1..=5).map(|i| point(12.0 * i as f64)).collect()));
    driver.screenshot("05-gizmo-dragging.png");
    driver.pointer(json!([point(90.0), { "type": "pointerUp", "button": 0 }]));
    let text = wait_text(&f, "the drag", |t| t != before_drag);
    let translate = ball_translate(&text);
    assert!(translate[0] > 0.8, "dragging the X arrow right moved the ball to {translate:?}");
    assert_eq!((translate[1], translate[2]), (0.0, 0.0), "the drag left the X axis: {translate:?}");
    driver.wait_for("the dragged ball in the panel", "return document.getElementById('tf-translate-0')?.value", |v| {
        v.as_str().and_then(|v| v.parse::<f64>().ok()).is_some_and(|x| (x - translate[0]).abs() < 1e-6)
    });
    driver.screenshot("06-gizmo-dropped.png");
    // A drag is one undoable edit.
    driver.click("#undo");
    wait_text(&f, "the drag's undo", |t| t == before_drag);

    // Four views: the ball is outlined in each (top, front, right, perspective)
    driver.click("#layout");
    let quadrants = driver
        .wait_for("the outline in four views", OUTLINE_PIXELS, |v| (0..4).all(|i| v[i + 1].as_u64().unwrap_or(0) > 20));
    let quadrants: Vec<u64> = (1..5).map(|i| quadrants[i].as_u64().unwrap()).collect();
    driver.screenshot("07-four-views.png");
    driver.click("#layout");
    driver.wait_for("one view again", OUTLINE_PIXELS, |v| v[0].as_u64().unwrap_or(0) > 200);
    assert!(quadrants.iter().all(|&n| n > 20), "{quadrants:?}");

    // Delete, then undo
    driver.click("#delete");
    wait_text(&f, "the deletion", |t| !t.contains("name = \"ball\""));
    driver.wait_for("the tree without the ball", "return document.querySelectorAll('[id^=tree-shape-]').length", |v| {
        v == 2
    });
    driver.screenshot("08-deleted.png");
    driver.click("#undo");
    let text = wait_text(&f, "the undo", |t| t.contains("name = \"ball\""));
    assert!(text.contains("translate = [0.75, 0, 0]"), "{text}");
    driver
        .wait_for("the tree with the ball", "return document.querySelectorAll('[id^=tree-shape-]').length", |v| v == 3);
    driver.screenshot("09-undone.png");

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
    driver.screenshot("10-saved.png");
    // No error was shown on the way.
    let error = driver.script("return document.body.dataset.lastError || ''");
    assert_eq!(error, "", "the page showed an error");
}

#[test]
fn browser_shows_instances_and_picks_a_texture() {
    let f = Fixture::with(photonix::editor::BackendChoice::Cpu, |o| {
        o.preview_size = 96;
        let text = format!("{}{}", editor_support::SCENE, editor_support::INSTANCES);
        // Seen from further back, so the copies are in view.
        let text = text.replace("position = [0, 1, 4]   # the eye", "position = [0, 3, 7]   # the eye");
        std::fs::write(&o.scene, text).unwrap();
    });
    let mut image = image::RgbImage::new(4, 4);
    for (x, y, p) in image.enumerate_pixels_mut() {
        *p = if (x + y) % 2 == 0 { image::Rgb([230, 200, 40]) } else { image::Rgb([40, 60, 200]) };
    }
    image.save(f.dir.path().join("checker.png")).unwrap();
    let driver = Driver::start();
    driver.session("POST", "/url", json!({ "url": f.server().url() }));
    driver.wait_for("the first rendered frame", "return Number(document.body.dataset.frames || 0)", |v| {
        v.as_u64().unwrap_or(0) >= 1
    });
    driver.click("#shading");

    // The instances in the tree: the grid says how many copies it places
    let labels =
        driver.script("return [...document.querySelectorAll('[id^=tree-instance-]')].map((e) => e.textContent)");
    assert_eq!(labels, json!(["single (post)", "fence (post ×6)", "pairs (pair ×2)"]));
    driver.click("#tree-instance-1");
    driver.wait_for("the grid to be selected", "return document.body.dataset.selection", |v| v == "instance:1");
    let object = driver.script("return document.getElementById('obj-object').value");
    assert_eq!(object, "post");
    let note = driver.script("return document.getElementById('instance-note').textContent");
    assert!(note.as_str().unwrap().starts_with("6 copies of object \"post\", drawn whole"), "{note}");
    // Its six copies are outlined together.
    driver.wait_for("the grid's outline", OUTLINE_PIXELS, |v| v[0].as_u64().unwrap_or(0) > 200);
    driver.screenshot("11-instances-selected.png");

    // Move the grid by a typed value
    driver.type_into("#tf-translate-1", "0.5\n");
    let text = wait_text(&f, "the grid's move", |t| t.contains("transform = { translate = [-1.5, 0.5, -1.5] }"));
    assert!(text.contains("name = \"fence\""));
    let moved = driver.wait_for(
        "the moved copies",
        "const o = window.photonixEditor.viewport.objects.find((o) => o.target.kind === 'instance' && o.target.index === 1);
         o.mesh.geometry.computeBoundingBox(); const b = o.mesh.geometry.boundingBox.clone().applyMatrix4(o.mesh.matrixWorld);
         return b.min.y;",
        |v| v.as_f64().is_some_and(|y| (y - 0.5).abs() < 1e-4),
    );
    assert!((moved.as_f64().unwrap() - 0.5).abs() < 1e-4);
    driver.screenshot("12-instances-moved.png");

    // The texture picker: the ball's material, its reflectance, the folder's checker image
    driver.click("#tree-shape-1");
    driver.wait_for("the ball to be selected", "return document.body.dataset.selection", |v| v == "shape:1");
    driver.wait_for("the folder's images", "return document.getElementById('tex-file')?.dataset.loaded", |v| v == "1");
    let field = driver.script("return document.getElementById('tex-field').value");
    assert_eq!(field, "reflectance");
    let frames = driver.script("return Number(document.body.dataset.frames)").as_u64().unwrap();
    driver.click("#tex-file option[value='checker.png']");
    let text = wait_text(&f, "the texture", |t| t.contains("reflectance = { texture = \"checker\" }"));
    assert!(text.contains("[textures.checker]\ntype = \"image\"\nfile = \"checker.png\""), "{text}");
    let scene = photonix::scene::parse_scene(&text, &f.scene).unwrap();
    assert_eq!(scene.textures.len(), 1);
    driver.wait_for("the texture in the panel", "return document.getElementById('mat-reflectance')?.value", |v| {
        v == r#"{"texture":"checker"}"#
    });
    driver.screenshot("13-texture-picked.png");
    driver.click("#shading");
    driver.wait_for("a frame with the texture", "return Number(document.body.dataset.frames)", |v| {
        v.as_u64() > Some(frames + 1)
    });
    driver.screenshot("14-texture-rendered.png");

    // Saved: the file has the texture and the moved grid
    driver.click("#save");
    let start = Instant::now();
    loop {
        let saved = std::fs::read_to_string(&f.scene).unwrap();
        if saved.contains("texture = \"checker\"") {
            assert!(saved.contains("translate = [-1.5, 0.5, -1.5]"), "{saved}");
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(30), "the save did not reach the file:\n{saved}");
        std::thread::sleep(Duration::from_millis(50));
    }
    let error = driver.script("return document.body.dataset.lastError || ''");
    assert_eq!(error, "", "the page showed an error");
}
