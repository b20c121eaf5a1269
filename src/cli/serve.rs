//! `photonix serve`: starts the editor's server on a scene and prints the URL to open.

use std::net::IpAddr;
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::BackendArg;
use photonix::editor::{BackendChoice, ServeOptions, Server};
use photonix::gpu::{list_devices, GpuOptions};
use photonix::render::{auto_backend, Backend};

#[derive(clap::Args)]
pub struct ServeArgs {
    /// Scene file to edit (TOML, see docs/scene-format.md; a .pov or a glTF scene (.glb, .gltf) is translated and saved as .toml beside it); the editor reads and writes only its folder
    scene: PathBuf,
    /// Address to listen on; anything but 127.0.0.1 or ::1 lets other machines reach the editor (with the token)
    #[arg(long, default_value = "127.0.0.1")]
    host: IpAddr,
    /// Port to listen on [default: a free one]
    #[arg(long, default_value_t = 0)]
    port: u16,
    /// Where the preview and the final render run: a real GPU when there is one, else the CPU (auto)
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
    /// Vulkan device: index or name substring (see `photonix devices`); GPU backend only
    #[arg(long)]
    device: Option<String>,
    /// Longest side of the rendered preview in pixels, 16 to 4096
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(16..=4096))]
    preview_size: u32,
    /// Access token (16 to 128 letters, digits, `-` or `_`) [default: a random one]; give the
    /// one printed before, with the same --port, and pages left open reconnect after a restart
    #[arg(long)]
    token: Option<String>,
    /// Largest mesh import in MiB, 1 to 4096
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(1..=4096))]
    max_upload_mib: u64,
}

pub fn run(args: ServeArgs) -> Result<()> {
    if args.device.is_some() && matches!(args.backend, BackendArg::Cpu) {
        anyhow::bail!("--device picks a Vulkan device, but --backend cpu uses none; leave one of them out");
    }
    let options = GpuOptions::from_env(args.device.clone())?;
    let (backend, why) = match args.backend {
        BackendArg::Gpu => (BackendChoice::Gpu { options, fallback: false }, "--backend gpu".to_string()),
        BackendArg::Cpu => (BackendChoice::Cpu, "--backend cpu".to_string()),
        BackendArg::Auto => match auto_backend(&list_devices(), args.device.is_some()) {
            (Backend::Gpu, why) => {
                (BackendChoice::Gpu { options, fallback: args.device.is_none() }, format!("auto: {why}"))
            }
            (Backend::Cpu, why) => (BackendChoice::Cpu, format!("auto: {why}")),
        },
    };
    let mut serve = ServeOptions::new(args.scene.clone());
    serve.host = args.host;
    serve.port = args.port;
    serve.backend = backend;
    serve.preview_size = args.preview_size;
    serve.max_upload_bytes = (args.max_upload_mib << 20) as usize;
    serve.token = args.token.clone();

    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("cannot start the server's runtime")?;
    runtime.block_on(async {
        let server = Server::start(serve).await?;
        note!("photonix serve: editing {} on {} ({why})", args.scene.display(), server.device());
        if let Some(notice) = server.notice() {
            note!("note: {notice}");
        }
        if !server.addr.ip().is_loopback() {
            note!("warning: listening on {}: other machines can reach the editor; anyone with the URL can edit and save the scene", server.addr.ip());
        }
        note!("open this URL in a browser (it carries the access token; keep it private):");
        out!("    {}", server.url());
        note!("remote machine? tunnel first: ssh -L {0}:127.0.0.1:{0} <this host>, then open the URL on your own machine", server.addr.port());
        note!(
            "restart with --port {} --token {} and pages left open reconnect by themselves",
            server.addr.port(),
            server.token
        );
        note!("Ctrl-C stops the server (it asks again while edits are unsaved)");
        // Unsaved edits: the first Ctrl-C warns, a second within 10 s stops.
        loop {
            tokio::signal::ctrl_c().await.context("cannot wait for Ctrl-C")?;
            if !server.dirty() {
                break;
            }
            note!(
                "warning: {} has unsaved edits; save them in the page (Save or Ctrl+S), or press Ctrl-C again within 10 s to stop without them",
                args.scene.display()
            );
            match tokio::time::timeout(std::time::Duration::from_secs(10), tokio::signal::ctrl_c()).await {
                Ok(_) => {
                    note!("stopping; the unsaved edits are dropped");
                    break;
                }
                Err(_) => note!("still serving"),
            }
        }
        note!("stopping");
        server.shutdown().await;
        Ok::<(), anyhow::Error>(())
    })
}
