//! The editor's WebSocket: the scene on connect, rendered preview frames from the real renderer
//! (CPU backend, and the Vulkan kernels on lavapipe), edits answered and broadcast to every page,
//! and the token required. Prints the time from an edit to its first rendered frame (the
//! benchmark in BENCHMARKS.md quotes such runs; nothing here asserts a time).

mod editor_support;

use std::time::{Duration, Instant};

use editor_support::Fixture;
use futures_util::{SinkExt, StreamExt};
use photonix::editor::BackendChoice;
use serde_json::{json, Value};
use tokio_tungstenite::tungstenite::Message;

type Socket = tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn next(socket: &mut Socket) -> Option<Result<Message, tokio_tungstenite::tungstenite::Error>> {
    socket.next().await
}

async fn send(socket: &mut Socket, message: Message) -> Result<(), tokio_tungstenite::tungstenite::Error> {
    socket.send(message).await
}

/// A frame's header and PNG, or a JSON message.
enum Received {
    Frame(Value, Vec<u8>),
    Text(Value),
}

async fn receive(socket: &mut Socket) -> Received {
    loop {
        let message = tokio::time::timeout(Duration::from_secs(120), next(socket))
            .await
            .expect("a message within two minutes")
            .expect("the socket stays open")
            .expect("a well-formed message");
        match message {
            Message::Text(text) => return Received::Text(serde_json::from_str(text.as_str()).unwrap()),
            Message::Binary(bytes) => {
                let length = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
                let header: Value = serde_json::from_slice(&bytes[4..4 + length]).unwrap();
                return Received::Frame(header, bytes[4 + length..].to_vec());
            }
            _ => {}
        }
    }
}

async fn connect(f: &Fixture) -> Socket {
    let url = format!("ws://{}/ws?token={}", f.addr(), f.token());
    tokio_tungstenite::connect_async(url).await.expect("websocket connects").0
}

async fn send_json(socket: &mut Socket, value: Value) {
    send(socket, Message::Text(value.to_string().into())).await.unwrap();
}

const VIEW: &str =
    r#"{"type":"view","view":{"position":[0,1,4],"look_at":[0,0.5,0],"up":[0,1,0],"fov":45,"width":64,"height":48}}"#;

/// Connects, checks the scene arrives, asks for a view, waits for its frames, makes an edit
/// and measures the time to the first frame of the edited scene.
async fn stream_frames(f: &Fixture, label: &str) {
    let mut page = connect(f).await;
    let mut other = connect(f).await;
    match receive(&mut page).await {
        Received::Text(v) => {
            assert_eq!(v["type"], "scene");
            assert_eq!(v["shapes"].as_array().unwrap().len(), 3);
        }
        Received::Frame(..) => panic!("the scene comes first"),
    }
    send(&mut page, Message::Text(VIEW.into())).await.unwrap();
    // Frames of the first generation: quarter, half, then full size passes.
    let mut sizes = Vec::new();
    while sizes.len() < 3 {
        if let Received::Frame(header, png) = receive(&mut page).await {
            assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
            assert_eq!(header["kind"], "preview");
            sizes.push((header["width"].as_u64().unwrap(), header["height"].as_u64().unwrap()));
        }
    }
    assert_eq!(sizes, [(16, 12), (32, 24), (64, 48)], "{label}");

    // An edit: answered, broadcast to the other page, and rendered.
    let t = Instant::now();
    send_json(
        &mut page,
        json!({ "type": "edit", "id": 7, "command": {
        "op": "set", "target": { "material": "red" }, "field": "reflectance", "value": [0.1, 0.1, 0.7] } }),
    )
    .await;
    let mut replied = false;
    let mut first_frame = None;
    while !replied || first_frame.is_none() {
        match receive(&mut page).await {
            Received::Text(v) if v["type"] == "reply" => {
                assert_eq!(v["id"], 7);
                assert_eq!(v["ok"], true, "{v}");
                replied = true;
            }
            Received::Text(v) if v["type"] == "scene" => assert_eq!(v["revision"], 1),
            Received::Text(_) => {}
            Received::Frame(header, _) if replied || header["step"] == 0 => {
                // The first frame of a new generation is the quarter-size one.
                if header["step"] == 0
                    && header["since_change_ms"].as_f64().unwrap() < t.elapsed().as_secs_f64() * 1e3 + 1.0
                {
                    first_frame = Some((t.elapsed(), header));
                }
            }
            Received::Frame(..) => {}
        }
    }
    let (elapsed, header) = first_frame.unwrap();
    println!(
        "{label}: edit to first rendered frame {:.0} ms (server: {:.0} ms since the change, {:.0} ms rendering, {}x{})",
        elapsed.as_secs_f64() * 1e3,
        header["since_change_ms"].as_f64().unwrap(),
        header["render_ms"].as_f64().unwrap(),
        header["width"],
        header["height"]
    );
    // Only what the edit changed reaches the device: the material array (and the frame
    // constants, as the quick step has another size and no photons). The next full-size pass
    // of the same scene and view prepares and uploads nothing.
    let uploaded: Vec<&str> = header["uploaded"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    if label == "gpu" {
        assert_eq!(uploaded, ["frame", "materials"], "{header}");
    } else {
        assert!(uploaded.is_empty(), "{header}");
    }
    assert!(header["prepare_ms"].as_f64().unwrap() > 0.0, "{header}");
    loop {
        if let Received::Frame(h, _) = receive(&mut page).await {
            if h["generation"] == header["generation"] && h["step"].as_u64().unwrap() >= 3 {
                assert_eq!(h["uploaded"], json!([]), "{h}");
                assert_eq!(h["prepare_ms"], 0.0, "{h}");
                break;
            }
        }
    }
    // The other page got the new scene without asking.
    loop {
        if let Received::Text(v) = receive(&mut other).await {
            if v["type"] == "scene" && v["revision"] == 1 {
                assert_eq!(v["materials"][1]["fields"]["reflectance"], json!([0.1, 0.1, 0.7]));
                break;
            }
        }
    }
    // A malformed message gets an error and changes nothing.
    send(&mut page, Message::Text("{\"type\":\"edit\",\"command\":{\"op\":\"nope\"}}".into())).await.unwrap();
    loop {
        if let Received::Text(v) = receive(&mut page).await {
            if v["type"] == "error" {
                assert!(v["message"].as_str().unwrap().contains("malformed"), "{v}");
                break;
            }
        }
    }
    assert!(f.text().contains("reflectance = [0.1, 0.1, 0.7]"));
}

#[test]
fn websocket_streams_cpu_frames_and_broadcasts_edits() {
    let f = Fixture::with(BackendChoice::Cpu, |o| o.preview_size = 64);
    f.runtime.block_on(stream_frames(&f, "cpu"));
}

#[test]
fn websocket_streams_gpu_frames() {
    let options = photonix::gpu::GpuOptions::from_env(None).unwrap();
    let f = Fixture::with(BackendChoice::Gpu { options, fallback: false }, |o| o.preview_size = 64);
    assert!(f.server().device().starts_with("gpu"), "{}", f.server().device());
    f.runtime.block_on(stream_frames(&f, "gpu"));
}

/// Two pages, two views: each gets the frames of its own view only (the header's `owner`), and
/// the same view sent again does not restart the preview (switching Solid and Rendered).
#[test]
fn each_page_gets_the_frames_of_its_own_view() {
    let f = Fixture::with(BackendChoice::Cpu, |o| o.preview_size = 32);
    f.runtime.block_on(async {
        let mut a = connect(&f).await;
        let mut b = connect(&f).await;
        let view = |w: u32, h: u32| json!({ "type": "view", "view": { "position": [0, 1, 4], "look_at": [0, 0.5, 0], "up": [0, 1, 0], "fov": 45, "width": w, "height": h } });
        // The full-size frame of each view is 32 px on its longest side.
        async fn full_frame(page: &mut Socket) -> Value {
            loop {
                if let Received::Frame(header, _) = receive(page).await {
                    if header["step"].as_u64() >= Some(2) {
                        return header;
                    }
                }
            }
        }
        send_json(&mut a, view(64, 32)).await;
        let ha = full_frame(&mut a).await;
        assert_eq!((ha["width"].as_u64(), ha["height"].as_u64()), (Some(32), Some(16)), "{ha}");
        send_json(&mut b, view(32, 64)).await;
        let hb = full_frame(&mut b).await;
        assert_eq!((hb["width"].as_u64(), hb["height"].as_u64()), (Some(16), Some(32)), "{hb}");
        assert_ne!(ha["owner"], hb["owner"]);
        // The same view again goes on with the same generation (or, when its passes are all
        // done, sends nothing): no restart from the first step.
        send_json(&mut b, view(32, 64)).await;
        let deadline = Instant::now() + Duration::from_millis(1500);
        while Instant::now() < deadline {
            if let Ok(Some(Ok(Message::Binary(bytes)))) = tokio::time::timeout(Duration::from_millis(100), next(&mut b)).await {
                let length = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
                let header: Value = serde_json::from_slice(&bytes[4..4 + length]).unwrap();
                assert_eq!(header["generation"], hb["generation"], "the same view restarted the preview: {header}");
            }
        }
        // Page a saw no frame of b's view meanwhile: every frame waiting for it is its own.
        let deadline = Instant::now() + Duration::from_millis(500);
        while Instant::now() < deadline {
            if let Ok(Some(Ok(Message::Binary(bytes)))) =
                tokio::time::timeout(Duration::from_millis(100), next(&mut a)).await
            {
                let length = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
                let header: Value = serde_json::from_slice(&bytes[4..4 + length]).unwrap();
                assert_eq!(header["owner"], ha["owner"], "page a got another page's frame: {header}");
            }
        }
    });
}

#[test]
fn websocket_needs_the_token() {
    let f = Fixture::new();
    f.runtime.block_on(async {
        for url in [format!("ws://{}/ws", f.addr()), format!("ws://{}/ws?token=wrong", f.addr())] {
            let result = tokio_tungstenite::connect_async(url.clone()).await;
            assert!(result.is_err(), "{url} connected");
        }
    });
}

/// The benchmark of BENCHMARKS.md ("Editor preview"), not a timed test: run it by hand with
/// `cargo test --release --test editor_ws -- --ignored --nocapture`. On scenes/cornell-box.toml
/// at the default preview size (256 px), for each backend: the time from an edit to its first
/// rendered frame (quarter size, direct light) and to the first full-size frame, and the
/// full-size passes per second while nothing changes. Each edit is sent a different time after
/// a full-size frame (0 to 1.5 s), so that edits land in every stage of a pass, photon tracing
/// included. `PHOTONIX_BENCH_BACKENDS=cpu` or `=gpu` runs one backend.
#[test]
#[ignore]
fn editor_preview_benchmark() {
    // PHOTONIX_BENCH_DELAYS_MS=a,b,... sends the edits at other delays: a lavapipe pass of
    // cornell-box traces photons for its first 2-3 s, so edits past that land in the grid
    // builds and the camera kernel.
    let delays: Vec<u64> = match std::env::var("PHOTONIX_BENCH_DELAYS_MS") {
        Ok(list) => list.split(',').map(|d| d.trim().parse().expect("delays in ms, comma-separated")).collect(),
        Err(_) => vec![0, 100, 250, 400, 600, 800, 1100, 1500],
    };
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let only = std::env::var("PHOTONIX_BENCH_BACKENDS").unwrap_or_default();
    for gpu in [false, true] {
        if !only.is_empty() && only != if gpu { "gpu" } else { "cpu" } {
            continue;
        }
        let backend = if gpu {
            BackendChoice::Gpu { options: photonix::gpu::GpuOptions::from_env(None).unwrap(), fallback: false }
        } else {
            BackendChoice::Cpu
        };
        let runtime = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
        let mut options = photonix::editor::ServeOptions::new(scene.clone());
        options.backend = backend;
        let server = runtime.block_on(photonix::editor::Server::start(options)).unwrap();
        let label = server.device();
        runtime.block_on(async {
            let url = format!("ws://{}/ws?token={}", server.addr, server.token);
            let mut page = tokio_tungstenite::connect_async(url).await.unwrap().0;
            let view = json!({ "type": "view", "view": { "position": [278, 273, -800], "look_at": [278, 273, -799],
                "up": [0, 1, 0], "fov": 39.3, "width": 256, "height": 256 } });
            send_json(&mut page, view).await;
            // The next frame of at least `step` from a generation after `after`.
            async fn frame(page: &mut Socket, after: u64, step: u64) -> Value {
                loop {
                    if let Received::Frame(header, _) = receive(page).await {
                        if header["generation"].as_u64().unwrap() > after && header["step"].as_u64().unwrap() >= step {
                            return header;
                        }
                    }
                }
            }
            let mut generation = frame(&mut page, 0, 2).await["generation"].as_u64().unwrap();
            let (mut first, mut full) = (Vec::new(), Vec::new());
            let (mut quick_costs, mut full_costs, mut waits) = (Vec::new(), Vec::new(), Vec::new());
            let mut stages = Vec::new();
            for (i, delay) in delays.iter().enumerate() {
                tokio::time::sleep(Duration::from_millis(*delay)).await;
                let t = Instant::now();
                let value = [0.2 + 0.05 * i as f64, 0.1, 0.1];
                send_json(&mut page, json!({ "type": "edit", "command": {
                    "op": "set", "target": { "material": "red" }, "field": "reflectance", "value": value } })).await;
                let header = frame(&mut page, generation, 0).await;
                assert_eq!(header["step"], 0, "the first frame after an edit is the quick one");
                first.push(t.elapsed().as_secs_f64() * 1e3);
                let ms = |h: &Value, key: &str| h[key].as_f64().unwrap();
                quick_costs.push((ms(&header, "prepare_ms"), ms(&header, "upload_ms"), header["uploaded"].to_string()));
                // Server side: from the change to the quick step's start (the stale step
                // stopping), and the quick step itself.
                let render = ms(&header, "render_ms");
                waits.push(((ms(&header, "since_change_ms") - render).round(), render.round()));
                // Where the time went: the stopped step's stages before it stopped, the quick step's.
                stages.push(format!("stale {} / quick {}", header["stale"], header["stages"]));
                generation = header["generation"].as_u64().unwrap();
                let header = frame(&mut page, generation - 1, 2).await;
                full.push(t.elapsed().as_secs_f64() * 1e3);
                full_costs.push(ms(&header, "prepare_ms") + ms(&header, "upload_ms"));
            }
            let start = Instant::now();
            let mut passes = 0;
            let mut pass_costs = Vec::new();
            while passes < 4 && start.elapsed() < Duration::from_secs(8) {
                let h = frame(&mut page, generation - 1, 3).await;
                pass_costs.push(h["prepare_ms"].as_f64().unwrap() + h["upload_ms"].as_f64().unwrap());
                passes += 1;
            }
            println!("{label}: after an edit, the quick step's (prepare ms, upload ms, arrays written): {quick_costs:?}");
            println!("{label}: server side, (ms until the stale step stopped, ms of the quick step): {waits:?}");
            for (i, line) in stages.iter().enumerate() {
                println!("{label}: edit {i}: {line}");
            }
            println!(
                "{label}: prepare + upload of the first full-size pass (which every pass paid before) {:?} ms; of the passes after it {:?} ms",
                full_costs.iter().map(|v| (v * 10.0).round() / 10.0).collect::<Vec<_>>(),
                pass_costs
            );
            let fps = passes as f64 / start.elapsed().as_secs_f64();
            let mut sorted = first.clone();
            sorted.sort_by(f64::total_cmp);
            println!(
                "{label}: edit to first frame (64 px) {:?} ms (median {:.0}, max {:.0}); to first full-size frame (256 px) {:?} ms; {fps:.2} full-size passes/s",
                first.iter().map(|v| v.round()).collect::<Vec<_>>(),
                sorted[sorted.len() / 2],
                sorted[sorted.len() - 1],
                full.iter().map(|v| v.round()).collect::<Vec<_>>()
            );
        });
        runtime.block_on(server.shutdown());
    }
}

/// The editor's preview renders with the path tracer and with vertex connection and merging
/// (`[render] integrator = "pt" | "vcm"`) on both backends: their photon settings are left
/// unused, and the passes come as for photon mapping.
#[test]
fn websocket_streams_path_traced_and_vcm_frames() {
    for integrator in ["pt", "vcm"] {
        let cpu = (BackendChoice::Cpu, "cpu");
        let gpu = (
            BackendChoice::Gpu { options: photonix::gpu::GpuOptions::from_env(None).unwrap(), fallback: false },
            "gpu",
        );
        for (backend, label) in [cpu, gpu] {
            let f = Fixture::with(backend, |o| {
                o.preview_size = 32;
                let line = format!("passes = 2\nintegrator = \"{integrator}\"\n");
                let text = editor_support::SCENE.replace("passes = 2\n", &line);
                assert!(text.contains(&line));
                std::fs::write(&o.scene, text).unwrap();
            });
            f.runtime.block_on(async {
                let mut page = connect(&f).await;
                send(&mut page, Message::Text(VIEW.replace("64", "32").replace("48", "24").into())).await.unwrap();
                let mut frames = 0;
                while frames < 3 {
                    if let Received::Frame(header, png) = receive(&mut page).await {
                        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{label}");
                        assert_eq!(header["kind"], "preview", "{label}");
                        frames += 1;
                    }
                }
            });
            println!("{integrator} {label}: three preview frames");
        }
    }
}

/// The latency targets of issue 23, on the CPU backend: `scenes/showcase.toml` with a 160 px
/// preview, through the scene's own camera. N edits (`PHOTONIX_BENCH_EDITS`, default 15), each
/// sent a different time after a full-size frame (0 to 1.4 s, so that they land in every stage
/// of a pass), each changing a material's colour. Prints, per edit, the time from the change to
/// the first frame as the server stamps it (`since_change_ms`: the edit applied, the stale step
/// stopped, the quick step rendered), the same seen by the page (with the WebSocket round trip),
/// and the time to the first full-size (160 px) frame; then median and max of each.
#[test]
#[ignore]
fn editor_latency_benchmark() {
    let edits: usize = std::env::var("PHOTONIX_BENCH_EDITS").ok().and_then(|n| n.parse().ok()).unwrap_or(15);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.toml");
    let camera = photonix::scene::load_scene(&path).unwrap().camera;
    let runtime = tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
    let mut options = photonix::editor::ServeOptions::new(path);
    options.backend = BackendChoice::Cpu;
    // PHOTONIX_BENCH_PREVIEW_SIZE: the preview's long side (160 unless given); PHOTONIX_BENCH_DENOISE=0
    // turns the preview's denoising off (on by default where Open Image Denoise loads).
    let size: u64 = std::env::var("PHOTONIX_BENCH_PREVIEW_SIZE").ok().and_then(|n| n.parse().ok()).unwrap_or(160);
    let denoise = std::env::var("PHOTONIX_BENCH_DENOISE").map_or(true, |v| v != "0");
    options.preview_size = size as u32;
    let server = runtime.block_on(photonix::editor::Server::start(options)).unwrap();
    let label = format!("{} (denoise {})", server.device(), if denoise { "on" } else { "off" });
    runtime.block_on(async {
        let url = format!("ws://{}/ws?token={}", server.addr, server.token);
        let mut page = tokio_tungstenite::connect_async(url).await.unwrap().0;
        let view = json!({ "type": "view", "view": { "position": camera.position.to_array(),
            "look_at": camera.look_at.to_array(), "up": camera.up.to_array(), "fov": camera.fov_deg,
            "width": 640, "height": 640 } });
        send_json(&mut page, view).await;
        send_json(&mut page, json!({ "type": "denoise", "on": denoise })).await;
        async fn frame(page: &mut Socket, after: u64, step: u64) -> Value {
            loop {
                if let Received::Frame(header, _) = receive(page).await {
                    if header["generation"].as_u64().unwrap() > after && header["step"].as_u64().unwrap() >= step {
                        return header;
                    }
                }
            }
        }
        let full_size = frame(&mut page, 0, 2).await;
        assert_eq!((full_size["width"].as_u64(), full_size["height"].as_u64()), (Some(size), Some(size)));
        assert_eq!(full_size["denoised"].as_bool(), Some(denoise));
        let mut generation = full_size["generation"].as_u64().unwrap();
        let (mut server_first, mut page_first, mut page_full) = (Vec::new(), Vec::new(), Vec::new());
        let (mut server_full, mut steps) = (Vec::new(), Vec::new());
        for i in 0..edits {
            tokio::time::sleep(Duration::from_millis((i as u64 * 100) % 1500)).await;
            let t = Instant::now();
            let value = [0.1, 0.1 + 0.02 * i as f64, 0.6];
            send_json(
                &mut page,
                json!({ "type": "edit", "command": {
                "op": "set", "target": { "material": "blue" }, "field": "reflectance", "value": value } }),
            )
            .await;
            let header = frame(&mut page, generation, 0).await;
            assert_eq!(header["step"], 0, "the first frame after an edit is the quick one");
            page_first.push(t.elapsed().as_secs_f64() * 1e3);
            server_first.push(header["since_change_ms"].as_f64().unwrap());
            generation = header["generation"].as_u64().unwrap();
            // The steps up to the full-size one, each with its own render time (ms) and stages.
            let mut ladder = vec![(0, header["render_ms"].as_f64().unwrap().round(), header["stages"].clone())];
            let full = loop {
                let h = frame(&mut page, generation - 1, 1).await;
                ladder.push((
                    h["step"].as_u64().unwrap(),
                    h["render_ms"].as_f64().unwrap().round(),
                    h["stages"].clone(),
                ));
                if h["step"].as_u64().unwrap() >= 2 {
                    break h;
                }
            };
            assert_eq!(full["width"].as_u64(), Some(size));
            page_full.push(t.elapsed().as_secs_f64() * 1e3);
            server_full.push(full["since_change_ms"].as_f64().unwrap());
            steps.push(ladder);
        }
        let summary = |v: &[f64]| {
            let mut s = v.to_vec();
            s.sort_by(f64::total_cmp);
            format!(
                "{:?} ms (median {:.0}, max {:.0})",
                v.iter().map(|x| x.round()).collect::<Vec<_>>(),
                s[s.len() / 2],
                s[s.len() - 1]
            )
        };
        println!("{label}: showcase.toml, {size} px preview, {edits} edits");
        println!("{label}: edit to first frame at the server: {}", summary(&server_first));
        println!("{label}: edit to first frame at the page: {}", summary(&page_first));
        println!("{label}: edit to first full-size ({size} px) frame at the server: {}", summary(&server_full));
        println!("{label}: edit to first full-size ({size} px) frame at the page: {}", summary(&page_full));
        for (i, ladder) in steps.iter().enumerate() {
            println!("{label}: edit {i}: (step, render ms, stages) {ladder:?}");
        }
    });
    runtime.block_on(server.shutdown());
}

/// A binary PLY of a wavy `n` x `n` grid of quads (2 n² triangles) over [-1, 1]² at y 0.2.
fn wavy_grid_ply(n: usize) -> Vec<u8> {
    let side = n + 1;
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        side * side,
        2 * n * n
    )
    .into_bytes();
    for j in 0..side {
        for i in 0..side {
            let (x, z) = (i as f32 / n as f32 * 2.0 - 1.0, j as f32 / n as f32 * 2.0 - 1.0);
            let y = 0.2 + 0.05 * (x * 9.0).sin() * (z * 7.0).cos();
            for v in [x, y, z] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = (j * side + i) as i32;
            for tri in [[a, a + side as i32, a + 1], [a + 1, a + side as i32, a + side as i32 + 1]] {
                out.push(3);
                for v in tri {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
    }
    out
}

/// Issue 52: with a 100k-triangle mesh in the scene, the scene message after an edit of
/// something else (the ball's colour, the ball's position) does not carry the mesh again (17 MB
/// before). Prints the time from the edit's arrival at the server to its first frame and what
/// the renderer spent on it; the issue's target of 200 ms is not asserted: the renderer's
/// `prepare` of the whole scene (its BVH over the mesh) takes 240-360 ms of it on this 2-core
/// machine (BENCHMARKS.md, docs/editor.md).
#[test]
fn an_edit_beside_a_100k_triangle_mesh_sends_kilobytes_not_the_mesh() {
    let f = Fixture::with(BackendChoice::Cpu, |o| {
        std::fs::write(o.scene.with_file_name("terrain.ply"), wavy_grid_ply(224)).unwrap();
        let text = format!(
            "{}\n[[shapes]]\nname = \"terrain\"\ntype = \"mesh\"\nfile = \"terrain.ply\"\nmaterial = \"white\"\n",
            editor_support::SCENE
        );
        std::fs::write(&o.scene, text).unwrap();
        o.preview_size = 64;
    });
    let scene = f.scene_json();
    let triangles = scene["shapes"][3]["positions"].as_array().unwrap().len() / 9;
    assert!(triangles >= 100_000, "{triangles} triangles");
    f.runtime.block_on(async {
        // The first scene message carries the mesh (17 MB), past tungstenite's default limit.
        let url = format!("ws://{}/ws?token={}", f.addr(), f.token());
        let config = tokio_tungstenite::tungstenite::protocol::WebSocketConfig::default()
            .max_message_size(Some(64 << 20))
            .max_frame_size(Some(64 << 20));
        let mut page = tokio_tungstenite::connect_async_with_config(url, Some(config), false).await.unwrap().0;
        send(&mut page, Message::Text(VIEW.into())).await.unwrap();
        // The first generation's full-size frame: the renderer is warm.
        let mut generation = loop {
            if let Received::Frame(h, _) = receive(&mut page).await {
                if h["step"].as_u64() >= Some(2) {
                    break h["generation"].as_u64().unwrap();
                }
            }
        };
        let mut times = Vec::new();
        let mut sizes = Vec::new();
        for i in 0..6 {
            let command = if i % 2 == 0 {
                json!({ "op": "set", "target": { "material": "red" }, "field": "reflectance", "value": [0.7, 0.1 + 0.05 * i as f64, 0.1] })
            } else {
                json!({ "op": "set_transform", "target": { "shape": 1 }, "translate": [0.05 * i as f64, 0, 0] })
            };
            let t = Instant::now();
            send_json(&mut page, json!({ "type": "edit", "id": i, "command": command })).await;
            let (mut first, mut scene_bytes) = (None, None);
            while first.is_none() || scene_bytes.is_none() {
                match tokio::time::timeout(Duration::from_secs(120), next(&mut page)).await.unwrap().unwrap().unwrap() {
                    Message::Text(text) if text.as_str().starts_with("{\"type\":\"scene\"") || text.contains("\"type\":\"scene\"") => {
                        scene_bytes = Some(text.len());
                    }
                    Message::Binary(bytes) => {
                        let length = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
                        let header: Value = serde_json::from_slice(&bytes[4..4 + length]).unwrap();
                        if header["generation"].as_u64() > Some(generation) && first.is_none() {
                            generation = header["generation"].as_u64().unwrap();
                            // From the edit's arrival at the server (its receipt time).
                            first = Some((t.elapsed().as_secs_f64() * 1e3, header["since_edit_ms"].as_f64()));
                            println!(
                                "  since the scene reached the renderer {:.0} ms: prepare {:.0} ms, upload {:.0} ms, render {:.0} ms",
                                header["since_change_ms"].as_f64().unwrap_or(0.0),
                                header["prepare_ms"].as_f64().unwrap_or(0.0),
                                header["upload_ms"].as_f64().unwrap_or(0.0),
                                header["render_ms"].as_f64().unwrap_or(0.0)
                            );
                        }
                    }
                    _ => {}
                }
            }
            let (page_ms, server_ms) = first.unwrap();
            println!(
                "edit {i}: first frame {page_ms:.0} ms at the page, {} ms at the server; scene message {} bytes",
                server_ms.map_or("?".into(), |m| format!("{m:.0}")),
                scene_bytes.unwrap()
            );
            times.push(server_ms.unwrap_or(page_ms));
            sizes.push(scene_bytes.unwrap());
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        println!("median edit to first frame at the server: {median:.0} ms; scene messages {sizes:?} bytes");
        assert!(sizes.iter().all(|&s| s < 1 << 20), "scene messages carry the mesh again: {sizes:?} bytes");
    });
}
