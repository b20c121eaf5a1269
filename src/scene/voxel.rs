//! Voxel grid files (PXVOL1, documented in `docs/scene-format.md`): a density per voxel for
//! heterogeneous media, read and checked here; `render::pack` puts the values into the texture
//! data, where `shaders/voxel.glsl` looks them up.
//!
//! Layout, little-endian: the 8 bytes `PXVOL1\0\0`; nx, ny, nz as u32; the box the grid fills
//! (min x, y, z, max x, y, z) as f32; then nx ny nz f32 values, x fastest, then y, then z.

use std::path::Path;

use glam::Vec3;

/// The file's first 8 bytes.
pub const VOXEL_MAGIC: &[u8; 8] = b"PXVOL1\0\0";
/// Bytes before the values: magic, three dimensions, six bounds.
pub const VOXEL_HEADER_BYTES: usize = 8 + 12 + 24;
/// Most voxels along one axis.
pub const MAX_VOXEL_SIDE: u32 = 1024;
/// Most voxels in one grid: 2^24 values are 64 MiB, half of lavapipe's largest storage buffer
/// (the texture data holds them with the scene's other textures).
pub const MAX_VOXELS: u64 = 1 << 24;

/// A checked voxel grid.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelGrid {
    pub dims: [u32; 3],
    /// The box the grid fills, in texture space (its placement's transform moves it).
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    /// nx ny nz values, x fastest.
    pub values: Vec<f32>,
    /// The largest value (a medium's majorant is sigma_t times this).
    pub max: f32,
}

impl VoxelGrid {
    /// The file's bytes for this grid (tests and tools write grids with it).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = VOXEL_MAGIC.to_vec();
        for n in self.dims {
            out.extend(n.to_le_bytes());
        }
        for v in self.bounds_min.to_array().into_iter().chain(self.bounds_max.to_array()) {
            out.extend(v.to_le_bytes());
        }
        for v in &self.values {
            out.extend(v.to_le_bytes());
        }
        out
    }
}

/// Reads and checks a PXVOL1 file. The error says what is wrong (not the path: the caller names
/// the file and the scene line).
pub fn load_voxel_grid(path: &Path) -> Result<VoxelGrid, String> {
    let bytes = crate::scene::files::read(path, crate::limits::MAX_VOXEL_FILE_BYTES).map_err(|e| match e {
        e if e.not_found() => "voxel file not found (paths are relative to the scene file)".to_string(),
        e => format!("cannot read the voxel file: {e}"),
    })?;
    parse_voxel_grid(&bytes)
}

/// Checks and decodes the bytes of a PXVOL1 file.
pub fn parse_voxel_grid(bytes: &[u8]) -> Result<VoxelGrid, String> {
    if bytes.len() < VOXEL_MAGIC.len() || &bytes[..8] != VOXEL_MAGIC {
        let start: String = bytes.iter().take(8).map(|&b| if b.is_ascii_graphic() { b as char } else { '.' }).collect();
        return Err(format!(
            "not a PXVOL1 voxel file: it starts with \"{start}\", not \"PXVOL1\" and two zero bytes (see docs/scene-format.md)"
        ));
    }
    if bytes.len() < VOXEL_HEADER_BYTES {
        return Err(format!(
            "truncated voxel file: its header needs {VOXEL_HEADER_BYTES} bytes, the file has {}",
            bytes.len()
        ));
    }
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
    let f32_at = |i: usize| f32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
    let dims = [u32_at(8), u32_at(12), u32_at(16)];
    if dims.iter().any(|&n| n == 0 || n > MAX_VOXEL_SIDE) {
        return Err(format!(
            "voxel grid of {} x {} x {}: each side must be 1 to {MAX_VOXEL_SIDE}",
            dims[0], dims[1], dims[2]
        ));
    }
    let count = dims.iter().map(|&n| n as u64).product::<u64>();
    if count > MAX_VOXELS {
        return Err(format!(
            "voxel grid of {} x {} x {} = {count} voxels; at most {MAX_VOXELS} (see docs/limits.md)",
            dims[0], dims[1], dims[2]
        ));
    }
    let b: Vec<f32> = (0..6).map(|i| f32_at(20 + 4 * i)).collect();
    let (lo, hi) = (Vec3::new(b[0], b[1], b[2]), Vec3::new(b[3], b[4], b[5]));
    if !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()) {
        return Err(format!(
            "voxel grid bounds min [{}, {}, {}], max [{}, {}, {}]: each must be finite, min below max on every axis",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        ));
    }
    let want = VOXEL_HEADER_BYTES as u64 + 4 * count;
    if (bytes.len() as u64) < want {
        return Err(format!(
            "truncated voxel file: {} x {} x {} voxels need {want} bytes, the file has {} (wrong dimensions, or a cut-off file)",
            dims[0],
            dims[1],
            dims[2],
            bytes.len()
        ));
    }
    if bytes.len() as u64 > want {
        return Err(format!(
            "voxel file has {} bytes after its {} x {} x {} voxels ({want} bytes expected); wrong dimensions?",
            bytes.len() as u64 - want,
            dims[0],
            dims[1],
            dims[2]
        ));
    }
    let mut values = Vec::with_capacity(count as usize);
    let mut max = 0.0f32;
    for i in 0..count as usize {
        let v = f32_at(VOXEL_HEADER_BYTES + 4 * i);
        if !(v.is_finite() && v >= 0.0) {
            let (x, y, z) = (i as u32 % dims[0], i as u32 / dims[0] % dims[1], i as u32 / (dims[0] * dims[1]));
            return Err(format!(
                "voxel ({x}, {y}, {z}) is {v}; densities must be finite and >= 0 (value {} of the file, x fastest)",
                i
            ));
        }
        max = max.max(v);
        values.push(v);
    }
    Ok(VoxelGrid { dims, bounds_min: lo, bounds_max: hi, values, max })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> VoxelGrid {
        VoxelGrid {
            dims: [2, 3, 4],
            bounds_min: Vec3::new(-1.0, 0.0, 0.0),
            bounds_max: Vec3::new(1.0, 2.0, 0.5),
            values: (0..24).map(|i| i as f32 * 0.5).collect(),
            max: 11.5,
        }
    }

    #[test]
    fn round_trip() {
        assert_eq!(parse_voxel_grid(&grid().to_bytes()).unwrap(), grid());
    }

    #[test]
    fn bad_files_say_what_is_wrong() {
        let good = grid().to_bytes();
        let err = |bytes: &[u8]| parse_voxel_grid(bytes).unwrap_err();
        assert!(err(b"P3\n2 2\n").contains("not a PXVOL1"));
        assert!(err(&good[..30]).contains("header needs 44 bytes"));
        assert!(err(&good[..good.len() - 4]).contains("truncated"));
        let mut long = good.clone();
        long.extend([0; 4]);
        assert!(err(&long).contains("4 bytes after"));
        let mut zero = good.clone();
        zero[12..16].copy_from_slice(&0u32.to_le_bytes());
        assert!(err(&zero).contains("each side must be 1 to 1024"));
        let mut nan = good.clone();
        let at = VOXEL_HEADER_BYTES + 4 * 7;
        nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(err(&nan).contains("voxel (1, 0, 1) is NaN"), "{}", err(&nan));
        let mut neg = good.clone();
        neg[at..at + 4].copy_from_slice(&(-2.0f32).to_le_bytes());
        assert!(err(&neg).contains("is -2"));
        let mut flat = good;
        flat[32..36].copy_from_slice(&(-1.0f32).to_le_bytes()); // max x below min x
        assert!(err(&flat).contains("min below max"));
    }
}
