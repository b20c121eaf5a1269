//! `photonix serve`: a scene editor in the browser with a real-time photon-mapped preview
//! (docs/editor.md). The server (`server.rs`, axum on tokio) holds one scene (`document.rs`:
//! the file as a `toml_edit` document, edits as small commands checked by the scene parser)
//! and one renderer (`preview.rs`: a thread with the GPU or CPU backend kept alive between
//! frames); the page (`web/`, embedded by `assets.rs`) draws the geometry (`geometry.rs`) with
//! three.js and shows the rendered frames; `gltf.rs` writes the same geometry as glTF 2.0 for
//! the page's download and `photonix export`.

mod assets;
pub mod document;
pub mod geometry;
pub mod gltf;
mod pov_objects;
pub mod preview;
pub mod server;

pub use document::{Command, EditError, SaveError, SceneDocument, Target};
pub use preview::{BackendChoice, FinalRequest, View};
pub use server::{ServeError, ServeOptions, Server};
