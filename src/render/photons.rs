//! Photon-map parameters and the CPU build of the maps (emission, then the hashed grid): global,
//! caustic, and volume (collisions in media).

use crate::cpu::emit_photons::emit_photons;
use crate::cpu::grid_build::{build_grid, grid_params};
use crate::cpu::photon_index::PhotonIndex;
use crate::cpu::render::excluded_by_every_lookup;
use crate::cpu::MapsView;
use crate::layout::{EmitParams, GridParams, Photon};

use super::SceneBuffers;

pub use crate::scene::PhotonSettings;

/// Average photons inside a lookup disc the automatic global radius aims at. 64 while the discs
/// darkened every edge; with the edge probes a wider disc pays: 160 lowered ppm's error at 30 s
/// by 23% on cornell-box and 11% on cornell-caustics on the CPU, 23% on the box through lavapipe
/// (BENCHMARKS.md, "Edges").
pub const GLOBAL_NEIGHBOURS: f32 = 160.0;
/// The automatic caustic radius is this fraction of the global one: caustic photons crowd
/// into small bright areas, so they afford a sharper filter.
pub const CAUSTIC_RADIUS_FRACTION: f32 = 0.5;

/// Emission parameters of the global (`caustics_only` = 0) or caustic pass `pass`.
pub fn emit_params(settings: &PhotonSettings, pass: u32, caustics_only: bool) -> EmitParams {
    let paths = if caustics_only { settings.caustic_photons } else { settings.photons };
    EmitParams {
        path_begin: 0,
        path_count: paths,
        total_paths: paths,
        max_depth: settings.max_depth,
        global_capacity: 0,
        caustic_capacity: 0,
        // Global and caustic passes draw disjoint random streams.
        pass: 2 * pass + caustics_only as u32,
        caustics_only: caustics_only as u32,
        volume_capacity: 0,
        _pad: [0; 3],
    }
}

/// `emit_params` of the caustic pass of `pass` for this scene: no paths where no caustic photon
/// can be stored (`SceneBuffers::can_store_caustics`).
pub fn caustic_emit_params(buffers: &SceneBuffers, settings: &PhotonSettings, pass: u32) -> EmitParams {
    let mut params = emit_params(settings, pass, true);
    if !buffers.can_store_caustics() {
        params.path_count = 0;
        params.total_paths = 0;
    }
    params
}

/// `emit_photons` of all of `params`' paths, in slices of the thread's stop-check size
/// (`super::thread_stop_paths`) with a look at the stop flags before each: a stopped trace
/// returns the photons of the slices done (the render then stops before using them). Paths draw
/// their own random streams, so the slices together store the photons of one whole trace.
fn emit_stoppable(view: &crate::cpu::SceneView, params: &EmitParams) -> crate::cpu::emit_photons::PhotonMaps {
    let Some(slice) = super::thread_stop_paths() else { return emit_photons(view, params) };
    let mut maps = crate::cpu::emit_photons::PhotonMaps::default();
    let mut begin = 0;
    while begin < params.total_paths && !super::stop_requested() {
        let count = (params.total_paths - begin).min(slice.min(u32::MAX as u64) as u32);
        let part = emit_photons(view, &EmitParams { path_begin: begin, path_count: count, ..*params });
        maps.global.extend(part.global);
        maps.caustic.extend(part.caustic);
        maps.volume.extend(part.volume);
        begin += count;
    }
    maps
}

/// Average photons inside a lookup ball the automatic volume radius aims at.
pub const VOLUME_NEIGHBOURS: f32 = 64.0;

/// How the volume lookup radius shrinks: in 3D the estimate's variance goes as 1 / r^3, so
/// Knaus and Zwicker's schedule becomes r_i = r_1 i^((alpha - 1) / 3) (their section 4.3).
pub fn volume_radius_scale(alpha: f32, pass: u32) -> f32 {
    ((pass as f64 + 1.0).powf((alpha as f64 - 1.0) / 3.0)) as f32
}

/// The volume map's lookup radius of pass `pass` for `stored` collisions: the ball that holds
/// VOLUME_NEIGHBOURS of them on average were they spread evenly through the media's volume.
pub fn volume_radius(buffers: &SceneBuffers, settings: &PhotonSettings, stored: u32, pass: u32) -> f32 {
    let auto =
        (3.0 * VOLUME_NEIGHBOURS * buffers.media_volume / (4.0 * std::f32::consts::PI * stored.max(1) as f32)).cbrt();
    // Never wider than the bounding sphere: a map of a handful of photons would read them all.
    let auto = auto.min(buffers.bounding_radius.max(f32::MIN_POSITIVE));
    settings.volume_radius.unwrap_or(auto) * volume_radius_scale(settings.alpha, pass)
}

/// How the lookup radius shrinks from pass to pass: r_i = r_1 i^((alpha - 1) / 2) for pass
/// i = `pass` + 1 (Knaus and Zwicker 2011, "Progressive Photon Mapping: A Probabilistic
/// Approach"), so that both the variance and the bias of the mean over passes go to zero.
pub fn pass_radius_scale(alpha: f32, pass: u32) -> f32 {
    ((pass as f64 + 1.0).powf((alpha as f64 - 1.0) / 2.0)) as f32
}

/// The lookup radii (global, caustic) of pass `pass` for a global map of `global_stored` photons.
pub fn radii(buffers: &SceneBuffers, settings: &PhotonSettings, global_stored: u32, pass: u32) -> (f32, f32) {
    // Photons spread over the surfaces at about stored / area per unit area; the radius whose
    // disc holds GLOBAL_NEIGHBOURS of them on average.
    let auto = (GLOBAL_NEIGHBOURS * buffers.surface_area / (std::f32::consts::PI * global_stored.max(1) as f32)).sqrt();
    let global = settings.radius.unwrap_or(auto);
    let caustic = settings.caustic_radius.unwrap_or(global * CAUSTIC_RADIUS_FRACTION);
    let scale = pass_radius_scale(settings.alpha, pass);
    (global * scale, caustic * scale)
}

/// Refuses lookup radii the photon grid cannot use: so small next to the scene's coordinates that
/// cell indices (coordinate / radius) leave the 32-bit integers the kernels use, or larger than
/// the whole scene (every lookup would visit every photon).
pub fn check_radii(buffers: &SceneBuffers, settings: &PhotonSettings) -> Result<(), super::Refused> {
    use crate::limits::fmt_f32;
    let Some(root) = buffers.nodes.first() else { return Ok(()) };
    let extent =
        root.aabb_min.iter().chain(&root.aabb_max).map(|c| c.abs()).filter(|c| c.is_finite()).fold(0.0, f32::max);
    let smallest = extent / (1u32 << 30) as f32;
    let largest = 2.0 * buffers.bounding_radius;
    for (name, radius) in [
        ("radius", settings.radius),
        ("caustic radius", settings.caustic_radius),
        ("volume radius", settings.volume_radius),
    ] {
        let Some(r) = radius else { continue };
        if r < smallest {
            return Err(super::Refused(format!(
                "the photon {name} {} is too small for this scene, whose coordinates reach {}: grid cells would \
                 overflow; give at least {}",
                fmt_f32(r),
                fmt_f32(extent),
                fmt_f32(smallest)
            )));
        }
        if r > largest && largest > 0.0 {
            return Err(super::Refused(format!(
                "the photon {name} {} is larger than the whole scene (diameter {}); every lookup would visit every \
                 photon: give at most {}, or leave it out to derive one",
                fmt_f32(r),
                fmt_f32(largest),
                fmt_f32(largest)
            )));
        }
    }
    Ok(())
}

/// Grid parameters of one map: its photons' flux is relative to total power / paths.
pub fn map_grid(buffers: &SceneBuffers, radius: f32, stored: u32, paths: u32) -> GridParams {
    grid_params(radius, stored, buffers.frame.total_light_power / paths.max(1) as f32)
}

/// The maps built on the CPU: sorted photons and bucket starts (`MAP_*` order).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonMaps {
    pub grids: [GridParams; 3],
    pub global_photons: Vec<Photon>,
    pub global_starts: Vec<u32>,
    pub caustic_photons: Vec<Photon>,
    pub caustic_starts: Vec<u32>,
    pub volume_photons: Vec<Photon>,
    pub volume_starts: Vec<u32>,
}

/// One pass's photons, unsorted, and the grid parameters of their maps (`MAP_*` order).
struct Emitted {
    grids: [GridParams; 3],
    global: Vec<Photon>,
    caustic: Vec<Photon>,
    volume: Vec<Photon>,
}

/// Traces both passes of `pass` and sets their grids' parameters.
fn emit_maps(buffers: &SceneBuffers, settings: &PhotonSettings, pass: u32) -> Emitted {
    let view = buffers.view();
    let emitted = emit_stoppable(&view, &emit_params(settings, pass, false));
    let (global, volume) = (emitted.global, emitted.volume);
    let caustic = emit_stoppable(&view, &caustic_emit_params(buffers, settings, pass)).caustic;
    let (r_global, r_caustic) = radii(buffers, settings, global.len() as u32, pass);
    let g_global = map_grid(buffers, r_global, global.len() as u32, settings.photons);
    let g_caustic = map_grid(buffers, r_caustic, caustic.len() as u32, settings.caustic_photons);
    let r_volume = volume_radius(buffers, settings, volume.len() as u32, pass);
    let g_volume = map_grid(buffers, r_volume, volume.len() as u32, settings.photons);
    Emitted { grids: [g_global, g_caustic, g_volume], global, caustic, volume }
}

/// Traces both passes of `pass` and builds their grids, as the GPU does.
pub fn build_maps_cpu(buffers: &SceneBuffers, settings: &PhotonSettings, pass: u32) -> PhotonMaps {
    let Emitted { grids, global, caustic, volume } = emit_maps(buffers, settings, pass);
    let (global_photons, global_starts) = build_grid(&global, &grids[0]);
    let (caustic_photons, caustic_starts) = build_grid(&caustic, &grids[1]);
    let (volume_photons, volume_starts) = build_grid(&volume, &grids[2]);
    PhotonMaps { grids, global_photons, global_starts, caustic_photons, caustic_starts, volume_photons, volume_starts }
}

/// Traces both passes of `pass` into the CPU backend's lookup layout (the same photons and
/// sums as `build_maps_cpu`'s grids), leaving out the photons no lookup of the render reads.
pub fn build_indices_cpu(buffers: &SceneBuffers, settings: &PhotonSettings, pass: u32) -> IndexedMaps {
    let Emitted { grids, global, caustic, volume } = emit_maps(buffers, settings, pass);
    let dropped = excluded_by_every_lookup(settings.gather_rays);
    // Each build is mostly serial (a counting sort): the maps are built side by side.
    let (global, (caustic, volume)) = rayon::join(
        || PhotonIndex::build(&global, &grids[0], dropped[0]),
        || {
            rayon::join(
                || PhotonIndex::build(&caustic, &grids[1], dropped[1]),
                || PhotonIndex::build(&volume, &grids[2], dropped[2]),
            )
        },
    );
    let indices = [global, caustic, volume];
    IndexedMaps { grids, indices }
}

/// The maps of `build_indices_cpu`: grid parameters and lookup layouts (`MAP_*` order).
pub struct IndexedMaps {
    pub grids: [GridParams; 3],
    pub indices: [PhotonIndex; 3],
}

impl IndexedMaps {
    pub fn view(&self) -> MapsView<'_> {
        MapsView { grids: &self.grids, indices: &self.indices }
    }
}
