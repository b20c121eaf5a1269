//! The HTTP and WebSocket server of `photonix serve` (axum on tokio).
//!
//! Routes (every one behind the token, see `auth`):
//! - `GET /` and the page's assets, embedded in the binary (`assets.rs`);
//! - `GET /api/scene`: the scene as the page sees it (`geometry::scene_json`);
//! - `POST /api/edit` (a `Command` as JSON), `/api/undo`, `/api/redo`, `/api/save` (409 with
//!   `"replace_needed": true` where it would replace a file the editor did not open or last
//!   write; `?replace=true` saves over it);
//! - `GET /api/scene.toml`: the scene's current text (a download);
//! - `GET /api/scene.glb`: the scene's geometry as glTF 2.0 binary (`gltf.rs`, a download);
//! - `GET /api/kinds`: every kind of material, light, shape and medium with its fields and
//!   defaults (`scene::kinds::json`); `GET /kinds.js` is the same as a module the page imports;
//! - `GET /api/images`: the image files in the scene's folder (`{"images": ["textures/a.png"]}`),
//!   for the texture picker;
//! - `POST /api/import?name=F.glb&material=M&at=x,y,z&floor=true&size=S`: the body is written
//!   to F.glb in the scene's folder and a mesh shape using it is added (any model format the
//!   renderer reads: OBJ, glTF/.glb, PLY, 3DS, IFS, .bpt), with `material` (else the file's own
//!   materials), scaled to `size` across where it is more than 4 times off it, and its bounding
//!   box centred on `at` (with `floor`, standing on it) (one undo step);
//! - `POST /api/render` (`FinalRequest`), `/api/render/cancel`, `GET /api/render/status`,
//!   `GET /api/render/image.exr`, `/api/render/image.png`: the final render;
//! - `GET /ws`: the WebSocket; the server sends the scene (text, `{"type": "scene", ...}`), the
//!   final render's status, errors, and frames (binary: a u32 little-endian length, that many
//!   bytes of JSON header, then a PNG); the page sends `{"type": "view", "view": View}`, `{"type": "denoise", "on": bool}` (the preview's denoising toggle; the hello says
//!   whether it is on and, where the library is missing, why not: `denoise`, `denoiser_missing`),
//!   `{"type": "edit", "id", "command"}`, `undo`, `redo` and `save` (`"replace": true` to save
//!   over a file a plain save refuses, whose reply says `"replace_needed": true`) (each answered by a
//!   `{"type": "reply", "id", "ok", "error"}`); after the scene and the final render's status
//!   it sends `{"type": "hello", "session"}`, the page's session number. Each page's view is its own: the renderer
//!   renders the view last sent (by whichever page), and a page gets only the preview frames of
//!   its own view (the header's `owner`), so no tab shows another's render.

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use axum::body::Bytes;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{DefaultBodyLimit, Query, Request, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;
use serde::Deserialize;
use serde_json::{json, Value as Json};
use tokio::sync::broadcast;

use super::assets::asset;
use super::document::{Command, EditError, SaveError, SceneDocument};
use super::geometry::scene_json;
use super::preview::{encode_exr, encode_png, BackendChoice, Event, FinalRequest, Renderer, View};

/// Largest request body other than an import, and largest WebSocket message.
pub const MAX_REQUEST_BYTES: usize = 1 << 20;
/// Default largest import (`--max-upload`).
pub const DEFAULT_MAX_UPLOAD_BYTES: usize = 64 << 20;

/// How to serve.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    pub scene: PathBuf,
    /// 127.0.0.1 unless told otherwise.
    pub host: IpAddr,
    /// 0 picks a free port.
    pub port: u16,
    pub backend: BackendChoice,
    /// Longest side of the full-size preview, pixels.
    pub preview_size: u32,
    pub max_upload_bytes: usize,
    /// `None` makes a random one.
    pub token: Option<String>,
}

impl ServeOptions {
    pub fn new(scene: PathBuf) -> ServeOptions {
        ServeOptions {
            scene,
            host: IpAddr::from([127, 0, 0, 1]),
            port: 0,
            backend: BackendChoice::Cpu,
            preview_size: 256,
            max_upload_bytes: DEFAULT_MAX_UPLOAD_BYTES,
            token: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    #[error("{0}")]
    Scene(String),
    #[error("cannot listen on {addr}: {cause}")]
    Bind { addr: SocketAddr, cause: std::io::Error },
    #[error("renderer: {0}")]
    Renderer(String),
    #[error("access token: {0}")]
    Token(String),
}

struct App {
    doc: Mutex<SceneDocument>,
    renderer: Renderer,
    token: String,
    cookie: String,
    /// The scene as the page sees it, for the current revision: the JSON, and its text once a
    /// new page or `GET /api/scene` asked for it (a large mesh makes megabytes of it, which an
    /// edit's broadcast leaves out: `geometry::delta_message`).
    scene_json: Mutex<Option<Arc<String>>>,
    /// The geometry keys of the scene last broadcast, which every page has.
    sent_geometry: Mutex<std::collections::HashSet<String>>,
    /// Scene updates and replies that every page gets.
    updates: broadcast::Sender<Arc<String>>,
    max_upload_bytes: usize,
    /// The next page session's number (the owner of the views it sends).
    next_session: AtomicU64,
    /// Set when the server stops: every page's WebSocket closes, so the pages know.
    closing: tokio::sync::watch::Sender<bool>,
}

/// A running editor server.
pub struct Server {
    pub addr: SocketAddr,
    pub token: String,
    app: Arc<App>,
    shutdown: Option<tokio::sync::oneshot::Sender<()>>,
    task: Option<tokio::task::JoinHandle<()>>,
}

impl Server {
    /// Loads the scene, starts the renderer and listens; call inside a tokio runtime.
    pub async fn start(options: ServeOptions) -> Result<Server, ServeError> {
        let doc = SceneDocument::load(&options.scene).map_err(|e| ServeError::Scene(e.to_string()))?;
        let token = match options.token {
            Some(t) => check_token(t)?,
            None => random_token()?,
        };
        let backend = options.backend.clone();
        let preview_size = options.preview_size;
        let renderer = tokio::task::spawn_blocking(move || Renderer::start(backend, preview_size))
            .await
            .map_err(|e| ServeError::Renderer(e.to_string()))?
            .map_err(ServeError::Renderer)?;
        renderer.set_scene(Arc::new(doc.scene().clone()));
        let addr = SocketAddr::new(options.host, options.port);
        let listener = tokio::net::TcpListener::bind(addr).await.map_err(|cause| ServeError::Bind { addr, cause })?;
        let addr = listener.local_addr().map_err(|cause| ServeError::Bind { addr, cause })?;
        let (_, sent) = super::geometry::delta_message(&mut scene_message(&doc), &Default::default());
        let (updates, _) = broadcast::channel(64);
        let app = Arc::new(App {
            doc: Mutex::new(doc),
            renderer,
            cookie: format!("photonix_token_{}", addr.port()),
            token: token.clone(),
            scene_json: Mutex::new(None),
            sent_geometry: Mutex::new(sent),
            updates,
            max_upload_bytes: options.max_upload_bytes,
            next_session: AtomicU64::new(1),
            closing: tokio::sync::watch::channel(false).0,
        });
        let router = router(app.clone());
        let (tx, rx) = tokio::sync::oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let _ = axum::serve(listener, router)
                .with_graceful_shutdown(async {
                    let _ = rx.await;
                })
                .await;
        });
        Ok(Server { addr, token, app, shutdown: Some(tx), task: Some(task) })
    }

    /// The URL to open, with the token.
    pub fn url(&self) -> String {
        let host = match self.addr.ip() {
            IpAddr::V6(ip) => format!("[{ip}]"),
            IpAddr::V4(ip) => ip.to_string(),
        };
        format!("http://{host}:{}/?token={}", self.addr.port(), self.token)
    }

    /// The scene's current text (what a save would write).
    pub fn scene_text(&self) -> String {
        self.app.doc.lock().expect("document lock").text().to_string()
    }

    /// What was opened in place of the file named, and why (`SceneDocument::load`).
    pub fn notice(&self) -> Option<String> {
        self.app.doc.lock().expect("document lock").notice().map(str::to_string)
    }

    /// True when the scene has edits that are not saved (Ctrl-C warns about them).
    pub fn dirty(&self) -> bool {
        self.app.doc.lock().expect("document lock").dirty()
    }

    /// The renderer's device, e.g. "cpu (2 threads)".
    pub fn device(&self) -> String {
        self.app.renderer.device.clone()
    }

    /// Stops listening and waits for the server task; the renderer stops when the last
    /// reference to it goes.
    pub async fn shutdown(mut self) {
        // Close the pages' WebSockets first (a graceful shutdown waits for open connections).
        let _ = self.app.closing.send(true);
        if let Some(tx) = self.shutdown.take() {
            let _ = tx.send(());
        }
        if let Some(mut task) = self.task.take() {
            // Give the connections under way a moment, then go.
            if tokio::time::timeout(std::time::Duration::from_secs(2), &mut task).await.is_err() {
                task.abort();
            }
        }
        let app = self.app.clone();
        drop(self);
        // The renderer's thread joins in Drop; keep that off the async threads.
        let _ = tokio::task::spawn_blocking(move || drop(app)).await;
    }
}

/// A token given on the command line: 16 to 128 of `A-Z a-z 0-9 - _` (it travels in URLs and
/// cookies as is, and a short one could be guessed).
fn check_token(token: String) -> Result<String, ServeError> {
    let ok =
        (16..=128).contains(&token.len()) && token.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_');
    if ok {
        Ok(token)
    } else {
        Err(ServeError::Token(
            "--token takes 16 to 128 letters, digits, '-' or '_' (leave it out for a random one)".into(),
        ))
    }
}

fn random_token() -> Result<String, ServeError> {
    let mut bytes = [0u8; 24];
    getrandom::fill(&mut bytes).map_err(|e| ServeError::Token(e.to_string()))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

fn router(app: Arc<App>) -> Router {
    let upload_limit = app.max_upload_bytes;
    Router::new()
        .route("/api/scene", get(get_scene))
        .route("/api/scene.toml", get(download_scene))
        .route("/api/scene.glb", get(download_glb))
        .route("/api/images", get(list_images))
        .route("/api/kinds", get(get_kinds))
        .route("/kinds.js", get(get_kinds_module))
        .route("/api/edit", post(post_edit))
        .route("/api/undo", post(post_undo))
        .route("/api/redo", post(post_redo))
        .route("/api/save", post(post_save))
        .route("/api/import", post(post_import).layer(DefaultBodyLimit::max(upload_limit)))
        .route("/api/render", post(post_render))
        .route("/api/render/cancel", post(post_cancel))
        .route("/api/render/status", get(get_render_status))
        .route("/api/render/image.png", get(get_render_png))
        .route("/api/render/image.exr", get(get_render_exr))
        .route("/ws", get(websocket))
        .fallback(get(static_asset))
        .layer(DefaultBodyLimit::max(MAX_REQUEST_BYTES))
        .layer(middleware::map_response_with_state(app.clone(), json_errors))
        .layer(middleware::from_fn_with_state(app.clone(), auth))
        .with_state(app)
}

/// Every request needs the token: in the query (`?token=`, how the printed URL carries it), an
/// `Authorization: token <t>` header, or the cookie set on the first visit (so the page's own
/// module imports need not carry it). A request from a page of another origin is refused too.
async fn auth(State(app): State<Arc<App>>, request: Request, next: Next) -> Response {
    let query_token = request
        .uri()
        .query()
        .and_then(|q| q.split('&').find_map(|pair| pair.strip_prefix("token=").map(|t| t.to_string())));
    let header_token = request
        .headers()
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("token ").map(str::to_string));
    let cookie_token = request.headers().get_all(header::COOKIE).iter().find_map(|v| {
        v.to_str().ok()?.split(';').find_map(|c| {
            let (name, value) = c.trim().split_once('=')?;
            (name == app.cookie).then(|| value.to_string())
        })
    });
    let given = query_token.clone().or(header_token).or(cookie_token);
    match given {
        None => return error(StatusCode::UNAUTHORIZED, "missing token; open the URL that `photonix serve` printed"),
        Some(t) if !same_token(&t, &app.token) => {
            return error(StatusCode::FORBIDDEN, "wrong token; open the URL that `photonix serve` printed")
        }
        Some(_) => {}
    }
    if let Some(origin) = request.headers().get(header::ORIGIN) {
        let host = request.headers().get(header::HOST).and_then(|h| h.to_str().ok()).unwrap_or("");
        if origin.to_str().ok() != Some(&format!("http://{host}")) {
            return error(StatusCode::FORBIDDEN, "requests from other origins are refused");
        }
    }
    let mut response = next.run(request).await;
    let headers = response.headers_mut();
    if query_token.is_some() {
        let cookie = format!("{}={}; Path=/; HttpOnly; SameSite=Strict", app.cookie, app.token);
        if let Ok(v) = HeaderValue::from_str(&cookie) {
            headers.insert(header::SET_COOKIE, v);
        }
    }
    // The token is in the URL: no Referer may carry it elsewhere.
    headers.insert(header::REFERRER_POLICY, HeaderValue::from_static("no-referrer"));
    headers.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(
            "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; script-src 'self'; style-src 'self'; frame-ancestors 'none'",
        ),
    );
    headers.entry(header::CACHE_CONTROL).or_insert(HeaderValue::from_static("no-store"));
    response
}

/// Compares without an early exit, so the time taken says nothing about the token.
fn same_token(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// Replies that axum makes itself (a body over the limit: 413 in plain text) become JSON like
/// every other error of the API, so the page reads them the same way.
async fn json_errors(State(app): State<Arc<App>>, response: Response) -> Response {
    let json =
        response.headers().get(header::CONTENT_TYPE).is_some_and(|v| v.as_bytes().starts_with(b"application/json"));
    if response.status() == StatusCode::PAYLOAD_TOO_LARGE && !json {
        return error(
            StatusCode::PAYLOAD_TOO_LARGE,
            &format!(
                "the request is too large: at most {} for an edit or other request, {} for an import (--max-upload-mib)",
                crate::limits::fmt_bytes(MAX_REQUEST_BYTES as u64),
                crate::limits::fmt_bytes(app.max_upload_bytes as u64)
            ),
        );
    }
    response
}

fn error(status: StatusCode, message: &str) -> Response {
    (status, axum::Json(json!({ "ok": false, "error": message }))).into_response()
}

async fn static_asset(request: Request) -> Response {
    match asset(request.uri().path()) {
        Some((mime, bytes)) => ([(header::CONTENT_TYPE, mime)], bytes).into_response(),
        None => error(StatusCode::NOT_FOUND, "no such page"),
    }
}

fn scene_message(doc: &SceneDocument) -> Json {
    let mut value = scene_json(doc);
    value["type"] = json!("scene");
    value
}

/// The whole scene message as text (for a new page, `GET /api/scene`, a page that missed one),
/// made once per revision when asked for. Locks the document, then the text (as an edit does).
fn full_scene(app: &App) -> Arc<String> {
    if let Some(text) = app.scene_json.lock().expect("scene json lock").clone() {
        return text;
    }
    let doc = app.doc.lock().expect("document lock");
    let text = Arc::new(scene_message(&doc).to_string());
    *app.scene_json.lock().expect("scene json lock") = Some(text.clone());
    text
}

async fn get_kinds() -> Response {
    axum::Json(crate::scene::kinds::json()).into_response()
}

/// The declarations as `export const KINDS = {..};`, so the panels have them before they draw.
async fn get_kinds_module() -> Response {
    let module = format!("export const KINDS = {};\n", crate::scene::kinds::json());
    ([(header::CONTENT_TYPE, "text/javascript; charset=utf-8")], module).into_response()
}

async fn get_scene(State(app): State<Arc<App>>) -> Response {
    // Waits for the document (an edit under way) and may build megabytes: off the async threads.
    let json = tokio::task::block_in_place(|| full_scene(&app));
    ([(header::CONTENT_TYPE, "application/json")], json.to_string()).into_response()
}

async fn download_scene(State(app): State<Arc<App>>) -> Response {
    let (text, name) = {
        let doc = app.doc.lock().expect("document lock");
        (doc.text().to_string(), doc.path().file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default())
    };
    let name: String = name.chars().filter(|c| c.is_ascii_alphanumeric() || "._-".contains(*c)).collect();
    (
        [
            (header::CONTENT_TYPE, "application/toml; charset=utf-8".to_string()),
            (header::CONTENT_DISPOSITION, format!("attachment; filename=\"{name}\"")),
        ],
        text,
    )
        .into_response()
}

/// Most image files the texture picker lists.
const MAX_LISTED_IMAGES: usize = 1000;

async fn list_images(State(app): State<Arc<App>>) -> Response {
    let folder = app.doc.lock().expect("document lock").folder().to_path_buf();
    match tokio::task::spawn_blocking(move || super::document::image_files(&folder, MAX_LISTED_IMAGES)).await {
        Ok(images) => axum::Json(json!({ "images": images })).into_response(),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}

async fn download_glb(State(app): State<Arc<App>>) -> Response {
    let made = tokio::task::spawn_blocking(move || {
        let doc = app.doc.lock().expect("document lock");
        let stem = doc.path().file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let stem: String = stem.chars().filter(|c| c.is_ascii_alphanumeric() || "._-".contains(*c)).collect();
        super::gltf::scene_glb(&doc).map(|bytes| (bytes, format!("{stem}.glb")))
    })
    .await;
    match made {
        Ok(Ok((bytes, name))) => download(bytes, "model/gltf-binary", &name),
        Ok(Err(message)) => error(StatusCode::INTERNAL_SERVER_ERROR, &message),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}

/// What changes the document.
enum Change {
    Edit(Command),
    Undo,
    Redo,
}

/// Applies a change on a blocking thread (parsing a scene may read meshes), then sends the new
/// scene to every page and to the renderer. Returns the new revision.
async fn change(app: &Arc<App>, change: Change, author: u64) -> Result<u64, String> {
    let app2 = app.clone();
    let arrived = std::time::Instant::now();
    tokio::task::spawn_blocking(move || {
        let mut doc = app2.doc.lock().expect("document lock");
        let result = match &change {
            Change::Edit(command) => doc.apply_by(command, author),
            Change::Undo => doc.undo(),
            Change::Redo => doc.redo(),
        };
        result.map_err(|e: EditError| e.to_string())?;
        app2.renderer.set_scene_of_edit(Arc::new(doc.scene().clone()), arrived);
        broadcast_scene(&app2, &doc);
        Ok(doc.revision())
    })
    .await
    .map_err(|e| format!("the edit failed: {e}"))?
}

/// Sends the document's scene to the renderer and to every page.
fn publish(app: &App, doc: &SceneDocument) {
    app.renderer.set_scene(Arc::new(doc.scene().clone()));
    broadcast_scene(app, doc);
}

/// Sends the document's scene to every page (the renderer has it already): the geometry the
/// pages have already is left out (`geometry::delta_message`).
fn broadcast_scene(app: &App, doc: &SceneDocument) {
    let mut sent = app.sent_geometry.lock().expect("sent geometry lock");
    let mut value = super::geometry::scene_json_known(doc, &sent);
    value["type"] = json!("scene");
    let (delta, keys) = super::geometry::delta_message(&mut value, &sent);
    *sent = keys;
    *app.scene_json.lock().expect("scene json lock") = None;
    let _ = app.updates.send(Arc::new(delta));
}

fn reply(result: Result<u64, String>) -> Response {
    match result {
        Ok(revision) => axum::Json(json!({ "ok": true, "revision": revision })).into_response(),
        Err(message) => error(StatusCode::UNPROCESSABLE_ENTITY, &message),
    }
}

async fn post_edit(State(app): State<Arc<App>>, body: Bytes) -> Response {
    let command: Command = match serde_json::from_slice(&body) {
        Ok(c) => c,
        Err(e) => return error(StatusCode::BAD_REQUEST, &format!("malformed edit: {e}")),
    };
    reply(change(&app, Change::Edit(command), 0).await)
}

async fn post_undo(State(app): State<Arc<App>>) -> Response {
    reply(change(&app, Change::Undo, 0).await)
}

async fn post_redo(State(app): State<Arc<App>>) -> Response {
    reply(change(&app, Change::Redo, 0).await)
}

/// Saves; with `replace`, over a file the plain save leaves alone (the user said so).
async fn save(app: &Arc<App>, replace: bool) -> Result<u64, SaveError> {
    let app2 = app.clone();
    tokio::task::spawn_blocking(move || {
        let mut doc = app2.doc.lock().expect("document lock");
        doc.save_replacing(replace)?;
        broadcast_scene(&app2, &doc);
        Ok(doc.revision())
    })
    .await
    .map_err(|e| SaveError::Failed(format!("the save failed: {e}")))?
}

#[derive(Deserialize)]
struct SaveQuery {
    #[serde(default)]
    replace: bool,
}

/// `POST /api/save[?replace=true]`: a save that would replace another file is refused with 409
/// and `"replace_needed": true`, so the caller can ask and send `replace=true`.
async fn post_save(State(app): State<Arc<App>>, Query(query): Query<SaveQuery>) -> Response {
    match save(&app, query.replace).await {
        Ok(revision) => axum::Json(json!({ "ok": true, "revision": revision })).into_response(),
        Err(SaveError::WouldReplace(message)) => {
            (StatusCode::CONFLICT, axum::Json(json!({ "ok": false, "error": message, "replace_needed": true })))
                .into_response()
        }
        Err(SaveError::Failed(message)) => error(StatusCode::UNPROCESSABLE_ENTITY, &message),
    }
}

#[derive(Deserialize)]
struct ImportQuery {
    name: String,
    material: Option<String>,
    /// `x,y,z`: where the model's bounding box centre goes (with `floor`, the centre of its
    /// bottom face: it stands on the point).
    at: Option<String>,
    #[serde(default)]
    floor: bool,
    /// The size (bounding box diagonal, scene units) the model is scaled to when its own is
    /// more than 4 times larger or smaller (a model in millimetres in a scene in metres).
    size: Option<f64>,
}

/// The uniform scale that brings a model whose bounding box diagonal is `diagonal` to `size`,
/// when it is more than 4 times off (else 1), to 3 significant digits.
fn import_scale(diagonal: f64, size: Option<f64>) -> f64 {
    match size {
        Some(size) if size > 0.0 && diagonal > 0.0 && (diagonal > 4.0 * size || diagonal < size / 4.0) => {
            let k = size / diagonal;
            let digits = 10f64.powi(2 - k.log10().floor() as i32);
            (k * digits).round() / digits
        }
        _ => 1.0,
    }
}

/// The model formats the renderer reads (`scene::model::Format`), by extension.
const IMPORT_EXTENSIONS: [&str; 7] = ["obj", "gltf", "glb", "ply", "3ds", "ifs", "bpt"];

/// A file name for the scene's folder: letters, digits, `.`, `_`, `-`; no leading dot, no
/// path; the extension of a model format the renderer reads.
fn check_import_name(name: &str) -> Result<(), String> {
    let ok_chars = name.chars().all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
    if name.is_empty() || name.len() > 100 || !ok_chars || name.starts_with('.') {
        return Err(format!(
            "\"{}\" is not a file name the editor accepts: letters, digits, '.', '_' and '-', no folders",
            crate::limits::printable(name)
        ));
    }
    let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase()).unwrap_or_default();
    if !IMPORT_EXTENSIONS.contains(&ext.as_str()) {
        return Err(format!(
            "\"{}\" is not a model the renderer reads; import one of {}",
            crate::limits::printable(name),
            IMPORT_EXTENSIONS.iter().map(|e| format!(".{e}")).collect::<Vec<_>>().join(", ")
        ));
    }
    Ok(())
}

/// `x,y,z` as three finite numbers.
fn parse_point(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<f64> = text.split(',').filter_map(|p| p.trim().parse().ok()).collect();
    match parts[..] {
        [x, y, z] if parts.iter().all(|v| v.is_finite() && v.abs() < 1e9) => Ok([x, y, z]),
        _ => Err(format!("`at` takes three finite numbers x,y,z, not \"{}\"", crate::limits::printable(text))),
    }
}

async fn post_import(State(app): State<Arc<App>>, Query(query): Query<ImportQuery>, body: Bytes) -> Response {
    if let Err(message) = check_import_name(&query.name) {
        return error(StatusCode::BAD_REQUEST, &message);
    }
    let at = match query.at.as_deref().map(parse_point).transpose() {
        Ok(at) => at,
        Err(message) => return error(StatusCode::BAD_REQUEST, &message),
    };
    let app2 = app.clone();
    let result = tokio::task::spawn_blocking(move || -> Result<(u64, String), String> {
        let mut doc = app2.doc.lock().expect("document lock");
        // A name not taken yet: foo.obj, foo-2.obj, ...
        let (stem, ext) = query.name.rsplit_once('.').expect("checked: has a model extension");
        let mut name = query.name.clone();
        let mut n = 2;
        while std::fs::symlink_metadata(doc.folder().join(&name)).is_ok() {
            name = format!("{stem}-{n}.{ext}");
            n += 1;
        }
        let path = doc.folder().join(&name);
        crate::io::image::write_atomically(&path, |tmp| std::fs::write(tmp, &body).map_err(|e| e.to_string()))
            .map_err(|e| e.to_string())?;
        let mut table = serde_json::Map::new();
        table.insert("name".into(), json!(stem));
        table.insert("type".into(), json!("mesh"));
        if let Some(material) = &query.material {
            table.insert("material".into(), json!(material));
        }
        table.insert("file".into(), json!(name));
        let command = Command::Add { kind: super::document::Kind::Shape, table, name: None };
        if let Err(e) = doc.apply(&command) {
            // Nothing refers to the file: take it away again.
            let _ = std::fs::remove_file(&path);
            return Err(e.to_string());
        }
        // Centre it on `at`, in the same undo step as the import.
        let index = doc.origins().shapes.len().saturating_sub(1);
        let range = doc.origins().shapes.last().cloned().unwrap_or(0..0);
        let bounds = doc
            .scene()
            .shapes
            .get(range)
            .unwrap_or(&[])
            .iter()
            .map(|s| s.geometry.bounds())
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
        if let (Some(at), Some((lo, hi))) = (at, bounds) {
            let scale = import_scale((hi - lo).length() as f64, query.size);
            let centre = (lo + hi) * 0.5;
            let anchor = [centre.x as f64, if query.floor { lo.y as f64 } else { centre.y as f64 }, centre.z as f64];
            // The transform scales about the origin, then moves: the anchor lands on `at`.
            let translate = [0, 1, 2].map(|i| at[i] - scale * anchor[i]);
            let place = Command::SetTransform {
                target: super::document::Target::Shape(index),
                translate: Some(translate),
                rotate: None,
                scale: (scale != 1.0).then_some(super::document::Scale::Uniform(scale)),
            };
            if doc.apply(&place).is_ok() {
                doc.merge_last_step();
            }
        }
        publish(&app2, &doc);
        Ok((doc.revision(), name))
    })
    .await
    .unwrap_or_else(|e| Err(format!("the import failed: {e}")));
    match result {
        Ok((revision, file)) => axum::Json(json!({ "ok": true, "revision": revision, "file": file })).into_response(),
        Err(message) => error(StatusCode::UNPROCESSABLE_ENTITY, &message),
    }
}

async fn post_render(State(app): State<Arc<App>>, body: Bytes) -> Response {
    let request: FinalRequest = if body.is_empty() {
        FinalRequest::default()
    } else {
        match serde_json::from_slice(&body) {
            Ok(r) => r,
            Err(e) => return error(StatusCode::BAD_REQUEST, &format!("malformed render request: {e}")),
        }
    };
    let scene = Arc::new(app.doc.lock().expect("document lock").scene().clone());
    match app.renderer.start_final(request, scene) {
        Ok(()) => axum::Json(json!({ "ok": true })).into_response(),
        Err(message) => error(StatusCode::CONFLICT, &message),
    }
}

async fn post_cancel(State(app): State<Arc<App>>) -> Response {
    if app.renderer.cancel_final() {
        axum::Json(json!({ "ok": true })).into_response()
    } else {
        error(StatusCode::CONFLICT, "no final render is running")
    }
}

async fn get_render_status(State(app): State<Arc<App>>) -> Response {
    axum::Json(app.renderer.final_status()).into_response()
}

async fn get_render_png(State(app): State<Arc<App>>) -> Response {
    match app.renderer.final_image() {
        Some(image) => {
            let bytes = tokio::task::spawn_blocking(move || encode_png(&image, 0.0)).await.unwrap_or_default();
            download(bytes, "image/png", "render.png")
        }
        None => error(StatusCode::NOT_FOUND, "no final render yet; start one first"),
    }
}

async fn get_render_exr(State(app): State<Arc<App>>) -> Response {
    match app.renderer.final_image() {
        Some(image) => match tokio::task::spawn_blocking(move || encode_exr(&image)).await {
            Ok(Ok(bytes)) => download(bytes, "image/x-exr", "render.exr"),
            Ok(Err(message)) => error(StatusCode::INTERNAL_SERVER_ERROR, &message),
            Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
        },
        None => error(StatusCode::NOT_FOUND, "no final render yet; start one first"),
    }
}

fn download(bytes: Vec<u8>, mime: &'static str, name: &str) -> Response {
    let mut headers = HeaderMap::new();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(mime));
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{name}\"")) {
        headers.insert(header::CONTENT_DISPOSITION, v);
    }
    (headers, bytes).into_response()
}

async fn websocket(State(app): State<Arc<App>>, ws: WebSocketUpgrade) -> Response {
    ws.max_message_size(MAX_REQUEST_BYTES)
        .max_frame_size(MAX_REQUEST_BYTES)
        .on_upgrade(move |socket| session(app, socket))
}

/// A message from the page.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum PageMessage {
    View {
        view: View,
    },
    Edit {
        id: Option<u64>,
        command: Command,
    },
    Undo {
        id: Option<u64>,
    },
    Redo {
        id: Option<u64>,
    },
    /// `replace`: the user agreed to replace the file a plain save would not.
    Save {
        id: Option<u64>,
        #[serde(default)]
        replace: bool,
    },
    /// The preview's denoising toggle.
    Denoise {
        on: bool,
    },
}

/// A frame as the page reads it: a u32 little-endian length, that many bytes of JSON header,
/// then the PNG.
fn frame_bytes(header: &serde_json::Value, png: &[u8]) -> Vec<u8> {
    let header = header.to_string();
    let mut bytes = Vec::with_capacity(4 + header.len() + png.len());
    bytes.extend_from_slice(&(header.len() as u32).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(png);
    bytes
}

async fn session(app: Arc<App>, mut socket: WebSocket) {
    let me = app.next_session.fetch_add(1, Ordering::Relaxed);
    let mut closing = app.closing.subscribe();
    if *closing.borrow() {
        return;
    }
    let mut updates = app.updates.subscribe();
    let mut events = app.renderer.subscribe();
    let first = tokio::task::block_in_place(|| full_scene(&app));
    if socket.send(Message::Text(first.as_str().into())).await.is_err() {
        return;
    }
    let status = app.renderer.final_status();
    if socket.send(Message::Text(status.to_string().into())).await.is_err() {
        return;
    }
    // The page's own session number: its frames' `owner`, its steps' `undo_author`.
    let hello = json!({
        "type": "hello",
        "session": me,
        "denoise": app.renderer.denoise(),
        "denoiser_missing": app.renderer.denoiser,
    });
    if socket.send(Message::Text(hello.to_string().into())).await.is_err() {
        return;
    }
    // A page that comes after the preview converged gets its last frame, when it is everyone's
    // (the file's camera) rather than another page's view.
    if let Some(Event::Frame { header, png }) = app.renderer.last_preview() {
        if matches!(header["owner"].as_u64(), None | Some(0))
            && socket.send(Message::Binary(frame_bytes(&header, &png).into())).await.is_err()
        {
            return;
        }
    }
    loop {
        let outgoing = tokio::select! {
            _ = closing.changed() => {
                let _ = socket.send(Message::Close(None)).await;
                return;
            }
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Text(text))) => handle_page_message(&app, text.as_str(), me).await,
                Some(Ok(Message::Binary(_))) => Some(json!({ "type": "error", "message": "the editor takes text messages only" }).to_string()),
                Some(Ok(_)) => None,
                Some(Err(_)) | None => return,
            },
            update = updates.recv() => match update {
                Ok(json) => Some(json.to_string()),
                // Missed scene updates: send the current scene.
                Err(broadcast::error::RecvError::Lagged(_)) => Some(tokio::task::block_in_place(|| full_scene(&app)).to_string()),
                Err(broadcast::error::RecvError::Closed) => return,
            },
            event = events.recv() => match event {
                Ok(Event::Message(value)) => Some(value.to_string()),
                // Another page's view: not this page's render.
                Ok(Event::Frame { header, .. })
                    if header["kind"] == "preview"
                        && !matches!(header["owner"].as_u64(), None | Some(0))
                        && header["owner"].as_u64() != Some(me) =>
                {
                    None
                }
                Ok(Event::Frame { header, png }) => {
                    if socket.send(Message::Binary(frame_bytes(&header, &png).into())).await.is_err() {
                        return;
                    }
                    None
                }
                // A slow page skips frames; the next one is newer anyway.
                Err(broadcast::error::RecvError::Lagged(_)) => None,
                Err(broadcast::error::RecvError::Closed) => return,
            },
        };
        if let Some(text) = outgoing {
            if socket.send(Message::Text(text.into())).await.is_err() {
                return;
            }
        }
    }
}

/// Handles one message of a page; returns the reply to send, if any.
async fn handle_page_message(app: &Arc<App>, text: &str, session: u64) -> Option<String> {
    let message: PageMessage = match serde_json::from_str(text) {
        Ok(m) => m,
        Err(e) => return Some(json!({ "type": "error", "message": format!("malformed message: {e}") }).to_string()),
    };
    let (id, result) = match message {
        PageMessage::View { view } => {
            return app
                .renderer
                .set_view(view, session)
                .err()
                .map(|m| json!({ "type": "error", "message": m }).to_string());
        }
        PageMessage::Denoise { on } => {
            return app
                .renderer
                .set_denoise(on)
                .err()
                .map(|m| json!({ "type": "error", "message": format!("denoising: {m}") }).to_string());
        }
        PageMessage::Edit { id, command } => (id, change(app, Change::Edit(command), session).await),
        PageMessage::Undo { id } => (id, change(app, Change::Undo, session).await),
        PageMessage::Redo { id } => (id, change(app, Change::Redo, session).await),
        PageMessage::Save { id, replace } => match save(app, replace).await {
            Ok(revision) => (id, Ok(revision)),
            Err(SaveError::WouldReplace(message)) => {
                let reply = json!({ "type": "reply", "id": id, "ok": false, "error": message, "replace_needed": true });
                return Some(reply.to_string());
            }
            Err(SaveError::Failed(message)) => (id, Err(message)),
        },
    };
    let reply: Json = match result {
        Ok(revision) => json!({ "type": "reply", "id": id, "ok": true, "revision": revision }),
        Err(message) => json!({ "type": "reply", "id": id, "ok": false, "error": message }),
    };
    Some(reply.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn import_names_stay_in_the_folder() {
        assert!(check_import_name("bunny.obj").is_ok());
        assert!(check_import_name("My_Mesh-2.OBJ").is_ok());
        for good in ["a.glb", "a.gltf", "a.ply", "a.3DS", "a.ifs", "a.bpt"] {
            assert!(check_import_name(good).is_ok(), "{good}");
        }
        for bad in
            ["../x.obj", "a/b.obj", ".hidden.obj", "x.txt", "", "x\u{0}.obj", "/etc/x.obj", "..obj", "x.png", "obj"]
        {
            assert!(check_import_name(bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn imports_far_off_the_scenes_size_are_scaled_to_it() {
        assert_eq!(import_scale(1.0, Some(2.0)), 1.0);
        assert_eq!(import_scale(1.0, None), 1.0);
        assert_eq!(import_scale(300.0, Some(1.5)), 0.005);
        assert_eq!(import_scale(0.01, Some(1.0)), 100.0);
        assert_eq!(import_scale(3.0, Some(1.0)), 1.0);
    }

    #[test]
    fn tokens_compare_whole() {
        assert!(same_token("abc", "abc"));
        assert!(!same_token("abc", "abd"));
        assert!(!same_token("ab", "abc"));
    }
}
