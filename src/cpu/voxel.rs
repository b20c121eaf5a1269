//! Voxel grids (`TEXTURE_VOXELS`) and POV-Ray's ground fog (`TEXTURE_GROUND_FOG`) as densities;
//! twin of `shaders/voxel.glsl`.

use glam::{UVec3, Vec3};

use super::pattern::{lerp, turbulence_vector, vec3_at, word};
use crate::layout::constants::*;

fn voxel_at(data: &[u32], at: u32, n: UVec3, x: u32, y: u32, z: u32) -> f32 {
    f32::from_bits(data[(at + VOXEL_HEADER_WORDS + x + n.x * (y + n.y * z)) as usize])
}

/// The grid block at `at` (nx, ny, nz, then the values, x fastest) at `p` in its unit cube, by
/// trilinear interpolation between voxel centres ((i + 1/2) / n along each axis); the border
/// voxels' values hold out to the cube's faces, and the value is 0 outside the cube.
pub fn voxel_lookup(data: &[u32], at: u32, p: Vec3) -> f32 {
    if p.cmplt(Vec3::ZERO).any() || p.cmpgt(Vec3::ONE).any() {
        return 0.0;
    }
    let n = UVec3::new(data[at as usize], data[at as usize + 1], data[at as usize + 2]);
    let nf = n.as_vec3();
    let c = p * nf - 0.5;
    let x = c.clamp(Vec3::ZERO, nf - 1.0);
    let i0 = x.floor().as_uvec3();
    let i1 = (i0 + 1).min(n - 1);
    let f = x - i0.as_vec3();
    let v = |a: UVec3| voxel_at(data, at, n, a.x, a.y, a.z);
    let c00 = lerp(f.x, v(i0), v(UVec3::new(i1.x, i0.y, i0.z)));
    let c10 = lerp(f.x, v(UVec3::new(i0.x, i1.y, i0.z)), v(UVec3::new(i1.x, i1.y, i0.z)));
    let c01 = lerp(f.x, v(UVec3::new(i0.x, i0.y, i1.z)), v(UVec3::new(i1.x, i0.y, i1.z)));
    let c11 = lerp(f.x, v(UVec3::new(i0.x, i1.y, i1.z)), v(i1));
    lerp(f.z, lerp(f.y, c00, c10), lerp(f.y, c01, c11))
}

/// POV-Ray's ground fog density at texture-space point `p`: 1 at heights up to `offset`
/// (fog_offset), 1 / (1 + (y - offset) / alt)^2 above (alt: fog_alt), after moving the point by
/// turbulence when `turb_at` holds a pattern block (its turbulence amount, octaves, omega and
/// lambda), as POV-Ray's ground fog moves it.
pub fn ground_fog_density(data: &[u32], p: Vec3, offset: f32, alt: f32, turb_at: u32) -> f32 {
    let mut q = p;
    if turb_at != NO_DATA {
        let turb = vec3_at(data, turb_at + PATTERN_TURBULENCE);
        let octaves = data[(turb_at + PATTERN_OCTAVES) as usize];
        q = p + turbulence_vector(
            p,
            octaves,
            word(data, turb_at + PATTERN_OMEGA),
            word(data, turb_at + PATTERN_LAMBDA),
        ) * turb;
    }
    let h = (q.y - offset) / alt;
    if h.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return 1.0;
    }
    let k = 1.0 + h;
    1.0 / (k * k)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(n: [u32; 3], values: &[f32]) -> Vec<u32> {
        let mut data = vec![7u32]; // a leading word, so the block starts at 1
        data.extend(n);
        data.extend(values.iter().map(|v| v.to_bits()));
        data
    }

    /// A grid linear in x is reproduced exactly between the first and last voxel centres,
    /// held constant beyond them, and 0 outside the cube.
    #[test]
    fn trilinear_reproduces_a_linear_grid() {
        let n = [4u32, 2, 3];
        let values: Vec<f32> = (0..24).map(|i| (i % 4) as f32 * 2.0 + 1.0).collect::<Vec<_>>();
        let data = block(n, &values);
        for (x, want) in [(0.125f32, 1.0f32), (0.5, 4.0), (0.875, 7.0), (0.05, 1.0), (0.95, 7.0), (0.3125, 2.5)] {
            let got = voxel_lookup(&data, 1, Vec3::new(x, 0.4, 0.7));
            assert!((got - want).abs() < 1e-5, "x {x}: {got} vs {want}");
        }
        assert_eq!(voxel_lookup(&data, 1, Vec3::new(1.01, 0.5, 0.5)), 0.0);
        assert_eq!(voxel_lookup(&data, 1, Vec3::new(0.5, -0.01, 0.5)), 0.0);
    }

    #[test]
    fn ground_fog_falls_off_above_its_offset() {
        assert_eq!(ground_fog_density(&[], Vec3::new(0.0, -3.0, 0.0), 1.0, 2.0, NO_DATA), 1.0);
        assert_eq!(ground_fog_density(&[], Vec3::new(0.0, 1.0, 0.0), 1.0, 2.0, NO_DATA), 1.0);
        assert!((ground_fog_density(&[], Vec3::new(0.0, 3.0, 0.0), 1.0, 2.0, NO_DATA) - 0.25).abs() < 1e-6);
    }
}
