//! The memory a render takes, estimated before any of it is taken, so that a request too big for
//! the machine is refused up front, with what it would need and what fits, rather than ending in
//! an allocation failure (or swapping) half-way. docs/limits.md describes the model.

use super::photons::PhotonSettings;
use super::Refused;
use crate::cpu::grid_build::table_size_for;
use crate::layout::constants::LAYER_COUNT;
use crate::layout::Photon;
use crate::limits::fmt_bytes;

/// Host bytes per pixel: the running sums (4 layers + even/odd halves, 3 floats each), one
/// pass's output (4 layers + their sum), the per-pass sums the kernels accumulate into (a vec4
/// per layer), and the copies made while writing the files (mean, combined, encoder buffers).
pub const HOST_BYTES_PER_PIXEL: u64 = 72 + 60 + 16 * LAYER_COUNT as u64 + 120;
/// Device bytes per pixel of the accumulation buffer: a vec4 per layer (bounded by one storage
/// buffer; the image is rendered in bands of rows).
pub const DEVICE_BYTES_PER_PIXEL: u64 = 16 * LAYER_COUNT as u64;
/// Photons a global photon path is assumed to store (1.8 measured on cornell-box with its
/// albedos of about 0.7); a caustic path stores at most one.
pub const GLOBAL_PHOTONS_PER_PATH: u64 = 2;
/// Host bytes per photon path while a CPU pass traces (one list per path), and per stored photon
/// (traced, collected, sorted into the grid).
const HOST_BYTES_PER_PATH: u64 = 24;
const HOST_BYTES_PER_PHOTON: u64 = 24 + 24 + size_of::<Photon>() as u64;
/// The first photon buffer of a GPU pass has room for this many photons per path.
const GPU_PHOTONS_PER_PATH_GUESS: u64 = 4;

/// Where the memory of a render goes, in bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MemoryEstimate {
    /// (what, host bytes, device bytes)
    pub parts: Vec<(&'static str, u64, u64)>,
}

impl MemoryEstimate {
    pub fn host(&self) -> u64 {
        self.parts.iter().map(|p| p.1).fold(0, u64::saturating_add)
    }

    pub fn device(&self) -> u64 {
        self.parts.iter().map(|p| p.2).fold(0, u64::saturating_add)
    }

    /// `image 1.2 GiB, photon maps 3.0 GiB` for the host (`device` false) or the device.
    pub fn describe(&self, device: bool) -> String {
        let parts: Vec<String> = self
            .parts
            .iter()
            .map(|&(what, host, dev)| (what, if device { dev } else { host }))
            .filter(|&(_, bytes)| bytes > 0)
            .map(|(what, bytes)| format!("{what} {}", fmt_bytes(bytes)))
            .collect();
        parts.join(", ")
    }
}

/// The memory of a `width` x `height` render with these photon maps, on the GPU (`storage_limit`
/// = the device's largest storage buffer) or on the CPU (`None`).
pub fn estimate(
    width: u32,
    height: u32,
    photons: Option<&PhotonSettings>,
    storage_limit: Option<u64>,
) -> MemoryEstimate {
    let pixels = width as u64 * height as u64;
    let mut parts = Vec::new();
    let device_image = storage_limit.map_or(0, |limit| (pixels * DEVICE_BYTES_PER_PIXEL).min(limit));
    parts.push(("image", pixels * HOST_BYTES_PER_PIXEL, device_image));
    if let Some(p) = photons {
        let maps = [
            (p.photons as u64, p.photons as u64 * GLOBAL_PHOTONS_PER_PATH),
            (p.caustic_photons as u64, p.caustic_photons as u64),
        ];
        let (mut host, mut device) = (0u64, 0u64);
        for (paths, stored) in maps {
            let table = table_size_for(stored.min(u32::MAX as u64) as u32) as u64 * 4;
            let photon = size_of::<Photon>() as u64;
            match storage_limit {
                None => host += paths * HOST_BYTES_PER_PATH + stored * HOST_BYTES_PER_PHOTON + 2 * table,
                Some(limit) => {
                    // The traced photons, then two sorted copies during the grid build; the
                    // bucket counts and starts.
                    let first = (paths * GPU_PHOTONS_PER_PATH_GUESS * photon).min(limit);
                    device += first + 2 * (stored * photon).min(limit) + 2 * table;
                }
            }
        }
        parts.push(("photon maps", host, device));
    }
    MemoryEstimate { parts }
}

/// The scene's arrays as the device holds them: ("scene", 0, bytes), the part a GPU estimate
/// adds once the scene is prepared (the host's copy is counted by the prepared scene itself,
/// which exists before the estimate is made). Every array is split into pages of one texel view
/// (src/render/gpu/scene.rs), so only the device's memory bounds them, not one binding.
pub fn scene_part(buffers: &super::SceneBuffers) -> (&'static str, u64, u64) {
    let bytes = [
        size_of_val(buffers.nodes.as_slice()),
        size_of_val(buffers.primitives.as_slice()),
        size_of_val(buffers.materials.as_slice()),
        size_of_val(buffers.lights.as_slice()),
        size_of_val(buffers.textures.as_slice()),
        size_of_val(buffers.texture_data.as_slice()),
        size_of_val(buffers.shape_data.as_slice()),
        size_of_val(buffers.media.as_slice()),
    ];
    ("scene", 0, bytes.iter().map(|&b| b as u64).sum())
}

/// Refuses a render whose estimate does not fit the memory there is: `host_available` (see
/// `available_host_memory`) and, on the GPU, the device's memory (`device_available`). The
/// message says how much it would need, where, and what fits.
pub fn check_fits(
    e: &MemoryEstimate,
    width: u32,
    height: u32,
    photons: Option<&PhotonSettings>,
    host_available: Option<u64>,
    device_available: Option<u64>,
) -> Result<(), Refused> {
    let image_host = HOST_BYTES_PER_PIXEL * width as u64 * height as u64;
    if let Some(available) = host_available.filter(|&a| e.host() > a) {
        // What fits: the largest square image beside these photon maps, and the most photon paths
        // per map beside this image, where either fits at all.
        let maps_host = e.host() - image_host;
        let mut fits = Vec::new();
        if maps_host < available {
            let side = (((available - maps_host) / HOST_BYTES_PER_PIXEL) as f64).sqrt() as u64;
            fits.push(format!("at most about {side}x{side} pixels with these photon maps"));
        }
        if photons.is_some() && image_host < available {
            let per_path = 2 * HOST_BYTES_PER_PATH + (GLOBAL_PHOTONS_PER_PATH + 1) * HOST_BYTES_PER_PHOTON;
            fits.push(format!(
                "at most about {} photon paths per map at this size",
                (available - image_host) / per_path
            ));
        }
        let fits = if fits.is_empty() {
            "neither the image nor the photon maps alone fit".to_string()
        } else {
            fits.join(", or ")
        };
        return Err(Refused(format!(
            "this render needs about {} of memory ({}) but {} is available: {fits}; lower --resolution, --photons \
             or --caustic-photons (docs/limits.md explains the estimate)",
            fmt_bytes(e.host()),
            e.describe(false),
            fmt_bytes(available)
        )));
    }
    if let Some(available) = device_available.filter(|&a| e.device() > a) {
        return Err(Refused(format!(
            "this render needs about {} of device memory ({}) but the device has {}; lower --photons or \
             --caustic-photons, or use --backend cpu",
            fmt_bytes(e.device()),
            e.describe(true),
            fmt_bytes(available)
        )));
    }
    Ok(())
}

/// Refuses, on the GPU, photon maps that cannot fit one storage buffer (`storage_limit` bytes):
/// a path in a closed scene stores at least one photon, so more paths than the buffer holds
/// photons would fail only after tracing them all.
pub fn check_photon_buffer(photons: &PhotonSettings, storage_limit: u64) -> Result<(), Refused> {
    let photon = size_of::<Photon>() as u64;
    let most = storage_limit / photon;
    for (flag, paths) in [("--photons", photons.photons), ("--caustic-photons", photons.caustic_photons)] {
        if paths as u64 > most {
            return Err(Refused(format!(
                "{flag} {paths} would store at least {paths} photons ({}), more than one storage buffer holds on this \
                 device ({} = {most} photons); give at most {most}, or use --backend cpu",
                fmt_bytes(paths as u64 * photon),
                fmt_bytes(storage_limit)
            )));
        }
    }
    Ok(())
}

/// The host memory this process may still take: the kernel's MemAvailable, lowered by a cgroup
/// (container) limit when there is one. `None` where neither can be read.
pub fn available_host_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let available_kib: u64 = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    let mut available = available_kib * 1024;
    let read = |p: &str| std::fs::read_to_string(p).ok().and_then(|s| s.trim().parse::<u64>().ok());
    if let (Some(max), Some(current)) = (read("/sys/fs/cgroup/memory.max"), read("/sys/fs/cgroup/memory.current")) {
        available = available.min(max.saturating_sub(current));
    }
    Some(available)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimate_grows_with_pixels_and_photons_not_samples() {
        let small = estimate(64, 64, None, None);
        let large = estimate(640, 640, None, None);
        assert_eq!(large.host(), 100 * small.host());
        let p = PhotonSettings { photons: 1_000_000, caustic_photons: 1_000_000, ..PhotonSettings::default() };
        let with_maps = estimate(64, 64, Some(&p), None);
        // About 100 bytes per stored photon and 3 M photons: hundreds of MiB, not GiB.
        let maps = with_maps.host() - small.host();
        assert!((200 << 20..600 << 20).contains(&maps), "{}", fmt_bytes(maps));
        assert!(with_maps.describe(false).contains("photon maps"), "{}", with_maps.describe(false));
    }

    #[test]
    fn too_big_a_render_is_refused_with_what_fits() {
        let p = PhotonSettings::default();
        let e = estimate(16384, 16384, Some(&p), None);
        let message = check_fits(&e, 16384, 16384, Some(&p), Some(1 << 30), None).unwrap_err().to_string();
        assert!(message.contains("needs about 79."), "{message}");
        assert!(message.contains("1.0 GiB is available"), "{message}");
        assert!(message.contains("at most about 1"), "{message}");
        assert!(message.contains("pixels with these photon maps"), "{message}");
        let huge = PhotonSettings { photons: 1_000_000_000, caustic_photons: 1_000_000_000, ..p };
        let e = estimate(16384, 16384, Some(&huge), None);
        let message = check_fits(&e, 16384, 16384, Some(&huge), Some(1 << 30), None).unwrap_err().to_string();
        assert!(message.contains("neither the image nor the photon maps alone fit"), "{message}");
        assert!(check_fits(&e, 16384, 16384, Some(&p), Some(1 << 40), None).is_ok());
        let gpu = estimate(64, 64, Some(&p), Some(128 << 20));
        let message = check_fits(&gpu, 64, 64, Some(&p), None, Some(1 << 20)).unwrap_err().to_string();
        assert!(message.contains("device memory"), "{message}");
    }

    #[test]
    fn device_estimate_is_bounded_by_the_storage_buffer() {
        let limit = 128 << 20;
        let p = PhotonSettings { photons: 1_000_000_000, caustic_photons: 1, ..PhotonSettings::default() };
        let e = estimate(16384, 16384, Some(&p), Some(limit));
        // The image is rendered in bands; each photon buffer is at most one storage buffer.
        assert!(e.device() <= 8 * limit, "{}", fmt_bytes(e.device()));
        // The host keeps the image (about 316 bytes per pixel); the maps live on the device.
        assert!(e.host() > 64 << 30, "{}", fmt_bytes(e.host()));
    }
}
