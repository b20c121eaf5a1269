//! BVH build time and bytes per triangle on a large mesh (issue 13's benchmark).
//!
//! `cargo run --release --example bvh_build [SCENE]`: loads the scene (default: an icosahedron
//! under 8 levels of Loop subdivision, 1,310,720 triangles), then times each host stage on its
//! own: loading (parse, import, subdivision), packing the shapes, and the binned-SAH build; and
//! prints the bytes the traversal reads per triangle (nodes + primitives + shape data).
//! Rays per second on the same scene: `photonix bench SCENE`.

use std::error::Error;
use std::mem::size_of;
use std::path::PathBuf;
use std::time::Instant;

use photonix::accel::build_bvh;
use photonix::layout::{BvhNode, Primitive};
use photonix::render::pack::pack_scene;
use photonix::scene::load_scene;

const DEFAULT_SCENE: &str = r#"
[camera]
position = [0, 0.5, 3]
look_at = [0, 0, 0]
fov = 40
resolution = [256, 256]

[render]
spp = 4
passes = 1

[photons]
count = 100000
caustic_count = 1000

[materials.clay]
type = "diffuse"
reflectance = 0.6

[[shapes]]
type = "mesh"
file = "icosahedron.obj"
material = "clay"
subdivision = "loop"
levels = 8

[[lights]]
type = "point"
position = [2, 3, 3]
intensity = 30
"#;

fn main() -> Result<(), Box<dyn Error>> {
    let (path, temporary) = match std::env::args().nth(1) {
        Some(p) => (PathBuf::from(p), None),
        None => {
            // The scene beside a copy of the icosahedron, in a directory of its own.
            let dir = std::env::temp_dir().join(format!("photonix-bvh-bench-{}", std::process::id()));
            std::fs::create_dir_all(&dir)?;
            let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
            std::fs::copy(root.join("scenes/meshes/icosahedron.obj"), dir.join("icosahedron.obj"))?;
            std::fs::write(dir.join("big.toml"), DEFAULT_SCENE)?;
            (dir.join("big.toml"), Some(dir))
        }
    };
    let t = Instant::now();
    let scene = load_scene(&path)?;
    let load = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let packed = pack_scene(&scene);
    let pack = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let bvh = build_bvh(&packed.primitives, &packed.bounds)?;
    let build = t.elapsed().as_secs_f64();

    let n = packed.primitives.len();
    let node_bytes = bvh.nodes.len() * size_of::<BvhNode>();
    let primitive_bytes = bvh.primitives.len() * size_of::<Primitive>();
    let shape_bytes = packed.shape_data.len() * size_of::<f32>();
    let per = |bytes: usize| bytes as f64 / n as f64;
    println!(
        "{n} primitives; load {load:.3} s, pack {pack:.3} s, BVH build {build:.3} s ({:.2} M primitives/s)",
        n as f64 / build / 1e6
    );
    println!(
        "BVH: {} nodes of {} bytes, depth {}; bytes per primitive: nodes {:.1}, primitives {:.1}, shape data {:.1}, total {:.1}",
        bvh.nodes.len(),
        size_of::<BvhNode>(),
        bvh.depth,
        per(node_bytes),
        per(primitive_bytes),
        per(shape_bytes),
        per(node_bytes + primitive_bytes + shape_bytes)
    );
    if let Some(dir) = temporary {
        std::fs::remove_dir_all(dir)?;
    }
    Ok(())
}
