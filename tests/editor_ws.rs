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
/// rendered frame (quarter size) and to the first full-size frame, and the full-size passes per
/// second while nothing changes.
#[test]
#[ignore]
fn editor_preview_benchmark() {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    for gpu in [false, true] {
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
            let mut first = Vec::new();
            let mut full = Vec::new();
            let mut passes = (0, Instant::now());
            for edit in 0..3 {
                let t = Instant::now();
                if edit > 0 {
                    let value = [0.2 + 0.1 * edit as f64, 0.1, 0.1];
                    send_json(&mut page, json!({ "type": "edit", "command": {
                        "op": "set", "target": { "material": "red" }, "field": "reflectance", "value": value } })).await;
                }
                let mut got_first = false;
                loop {
                    if let Received::Frame(header, _) = receive(&mut page).await {
                        let step = header["step"].as_u64().unwrap();
                        if step == 0 && !got_first {
                            first.push(t.elapsed().as_secs_f64() * 1e3);
                            got_first = true;
                        }
                        if got_first && step == 2 {
                            full.push(t.elapsed().as_secs_f64() * 1e3);
                            passes = (0, Instant::now());
                        }
                        if got_first && step > 2 {
                            passes.0 += 1;
                            if passes.1.elapsed() > Duration::from_secs(4) || passes.0 >= 3 {
                                break;
                            }
                        }
                    }
                }
            }
            let fps = passes.0 as f64 / passes.1.elapsed().as_secs_f64();
            println!(
                "{label}: edit to first frame (64 px) {:?} ms; to first full-size frame (256 px) {:?} ms; {fps:.1} full-size passes/s",
                first.iter().map(|v| v.round()).collect::<Vec<_>>(),
                full.iter().map(|v| v.round()).collect::<Vec<_>>()
            );
        });
        runtime.block_on(server.shutdown());
    }
}
