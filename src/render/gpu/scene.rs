//! The scene arrays on the device: uploaded once, updated in place.

use crate::gpu::{Buffer, GpuContext, GpuError};
use crate::layout::constants::{NO_TEXTURE, SCENE_BINDINGS};
use crate::layout::Medium;
use crate::render::photons::PhotonSettings;
use crate::render::prepare::KernelVariant;
use crate::render::{photon_frame, SceneBuffers};

/// The scene arrays on the device.
pub struct DeviceScene {
    pub frame: Buffer,
    pub nodes: Buffer,
    pub primitives: Buffer,
    pub materials: Buffer,
    pub lights: Buffer,
    pub textures: Buffer,
    pub texture_data: Buffer,
    pub shape_data: Buffer,
    pub media: Buffer,
    /// Which variant of the scene kernels the scene needs.
    pub variant: KernelVariant,
}

impl DeviceScene {
    pub fn upload(
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<Self, GpuError> {
        let frame = photon_frame(buffers, photons);
        // Every array is one storage binding: refuse, with what it holds, one the device cannot bind.
        let limit = ctx.info().max_storage_buffer_range.min(ctx.info().max_memory_allocation_size);
        for (what, bytes) in [
            ("the scene's image and pattern textures", std::mem::size_of_val(buffers.texture_data.as_slice())),
            ("the scene's primitives", std::mem::size_of_val(buffers.primitives.as_slice())),
            ("the scene's BVH", std::mem::size_of_val(buffers.nodes.as_slice())),
            ("the scene's shape data (uv)", std::mem::size_of_val(buffers.shape_data.as_slice())),
        ] {
            if bytes as u64 > limit {
                return Err(GpuError::Unsupported(format!(
                    "{what} need {} MiB, more than one storage buffer holds on this device ({} MiB); use smaller images or fewer shapes, or --backend cpu",
                    (bytes as u64).div_ceil(1 << 20),
                    limit >> 20
                )));
            }
        }
        Ok(DeviceScene {
            frame: ctx.upload("frame", std::slice::from_ref(&frame))?,
            nodes: ctx.upload("bvh_nodes", &buffers.nodes)?,
            primitives: ctx.upload("primitives", &buffers.primitives)?,
            materials: ctx.upload("materials", &buffers.materials)?,
            lights: ctx.upload("lights", &buffers.lights)?,
            textures: ctx.upload("textures", &buffers.textures)?,
            texture_data: ctx.upload("texture_data", &buffers.texture_data)?,
            shape_data: ctx.upload("shape_data", &buffers.shape_data)?,
            media: ctx.upload("media", device_media(buffers))?,
            variant: buffers.variant(),
        })
    }

    /// Replaces the scene's arrays with those of `buffers`: an array of the same byte size is
    /// written into its existing buffer, any other gets a new buffer. Returns how many arrays were
    /// written in place (of 9).
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
    ) -> Result<u32, GpuError> {
        Ok(self.update_changed(ctx, buffers, photons, None)?.0)
    }

    /// [`DeviceScene::update`], leaving alone each array equal to that of `previous` (the scene
    /// and photon settings the device holds): an editor's change of one material writes the
    /// material array only. Returns how many arrays kept their buffer (of 9; unchanged ones
    /// count) and the names of the arrays written.
    pub fn update_changed(
        &mut self,
        ctx: &GpuContext,
        buffers: &SceneBuffers,
        photons: Option<&PhotonSettings>,
        previous: Option<(&SceneBuffers, Option<&PhotonSettings>)>,
    ) -> Result<(u32, Vec<&'static str>), GpuError> {
        fn replace<T: bytemuck::Pod>(
            ctx: &GpuContext,
            buffer: &mut Buffer,
            data: &[T],
            old: Option<&[T]>,
            written: &mut Vec<&'static str>,
            name: &'static str,
        ) -> Result<u32, GpuError> {
            let bytes = std::mem::size_of_val(data) as u64;
            if bytes == buffer.size()
                && old.is_some_and(|old| bytemuck::cast_slice::<T, u8>(old) == bytemuck::cast_slice::<T, u8>(data))
            {
                return Ok(1);
            }
            written.push(name);
            if bytes == buffer.size() {
                ctx.write(buffer, data)?;
                Ok(1)
            } else {
                *buffer = ctx.upload(buffer.name(), data)?;
                Ok(0)
            }
        }
        let frame = photon_frame(buffers, photons);
        let old_frame = previous.map(|(b, p)| photon_frame(b, p));
        self.variant = buffers.variant();
        let mut written = Vec::new();
        let w = &mut written;
        let kept = replace(
            ctx,
            &mut self.frame,
            std::slice::from_ref(&frame),
            old_frame.as_ref().map(std::slice::from_ref),
            w,
            "frame",
        )? + replace(ctx, &mut self.nodes, &buffers.nodes, previous.map(|(b, _)| &b.nodes[..]), w, "nodes")?
            + replace(
                ctx,
                &mut self.primitives,
                &buffers.primitives,
                previous.map(|(b, _)| &b.primitives[..]),
                w,
                "primitives",
            )?
            + replace(
                ctx,
                &mut self.materials,
                &buffers.materials,
                previous.map(|(b, _)| &b.materials[..]),
                w,
                "materials",
            )?
            + replace(ctx, &mut self.lights, &buffers.lights, previous.map(|(b, _)| &b.lights[..]), w, "lights")?
            + replace(
                ctx,
                &mut self.textures,
                &buffers.textures,
                previous.map(|(b, _)| &b.textures[..]),
                w,
                "textures",
            )?
            + replace(
                ctx,
                &mut self.texture_data,
                &buffers.texture_data,
                previous.map(|(b, _)| &b.texture_data[..]),
                w,
                "texture_data",
            )?
            + replace(
                ctx,
                &mut self.shape_data,
                &buffers.shape_data,
                previous.map(|(b, _)| &b.shape_data[..]),
                w,
                "shape_data",
            )?
            + replace(ctx, &mut self.media, device_media(buffers), previous.map(|(b, _)| device_media(b)), w, "media")?;
        Ok((kept, written))
    }

    /// The scene's buffers in binding order (`BINDING_*`, shaders/scene_bindings.glsl), followed
    /// by a kernel's own buffers.
    pub fn bindings<'a>(&'a self, own: &[&'a Buffer]) -> Vec<&'a Buffer> {
        let scene = [
            &self.frame,
            &self.nodes,
            &self.primitives,
            &self.materials,
            &self.lights,
            &self.textures,
            &self.texture_data,
            &self.shape_data,
            &self.media,
        ];
        debug_assert_eq!(scene.len(), SCENE_BINDINGS as usize);
        scene.into_iter().chain(own.iter().copied()).collect()
    }
}

/// The media as bound: Vulkan has no empty buffers, so a scene without media binds one unused.
fn device_media(buffers: &SceneBuffers) -> &[Medium] {
    const NONE: &[Medium] = &[Medium {
        sigma_a: [0.0; 3],
        phase: 0,
        sigma_s: [0.0; 3],
        g: 0.0,
        emission: [0.0; 3],
        density: NO_TEXTURE,
        bounds_min: [0.0; 3],
        majorant: 0.0,
        bounds_max: [0.0; 3],
        _pad: 0,
    }];
    if buffers.media.is_empty() {
        NONE
    } else {
        &buffers.media
    }
}
