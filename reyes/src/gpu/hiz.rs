//! The depth pyramid on the device: `hiz.wgsl`'s passes over one bucket's samples into the
//! target's pyramid buffer, which Bound reads for occlusion culling (twin and argument:
//! [`crate::stages::hiz`]).

use crate::frame::FrameUniforms;
use crate::stages::hiz::{HIZ_TILE_PX, capacity, levels};
use scheduler::{Gpu, RunError};

/// `HizParams` in hiz.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct HizParams {
    width: u32,
    height: u32,
    spp: u32,
    tile_px: u32,
    src_w: u32,
    src_h: u32,
    src_off: u32,
    dst_off: u32,
    dst_w: u32,
    dst_h: u32,
    pad: [u32; 2],
}

/// The two passes: level 0 from the samples, each level above from the one below.
pub(crate) struct HizPipelines {
    level0: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
}

impl HizPipelines {
    /// Compiles hiz.wgsl's entry points. Errors: a shader the device rejects.
    pub(crate) fn new(gpu: &Gpu) -> Result<HizPipelines, RunError> {
        Ok(HizPipelines {
            level0: gpu.compute_pipeline("reyes hiz level 0", crate::shaders::HIZ, "hiz_level0")?,
            reduce: gpu.compute_pipeline("reyes hiz reduce", crate::shaders::HIZ, "hiz_reduce")?,
        })
    }

    /// Records into `enc` the pyramid of the samples of `f`'s bucket into `hiz` (a buffer of
    /// [`capacity`] words for the target's pixels, `pixels`). Returns false, recording
    /// nothing, when the bucket's pyramid would not fit (never for a bucket of the target).
    pub(crate) fn record(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        f: &FrameUniforms,
        samples: &wgpu::Buffer,
        hiz: &wgpu::Buffer,
        pixels: u64,
    ) -> Result<bool, RunError> {
        match self.passes(gpu, f, samples, hiz, pixels)? {
            Some(p) => {
                self.record_passes(enc, &p);
                Ok(true)
            }
            None => Ok(false),
        }
    }

    /// The passes of [`HizPipelines::record`] with their parameters and bind groups, to be
    /// recorded any number of times ([`HizPipelines::record_passes`]; pipelined frames make
    /// them once). `None` when the bucket's pyramid would not fit.
    pub(crate) fn passes(
        &self,
        gpu: &Gpu,
        f: &FrameUniforms,
        samples: &wgpu::Buffer,
        hiz: &wgpu::Buffer,
        pixels: u64,
    ) -> Result<Option<HizPasses>, RunError> {
        let lv = levels(f.tile_w, f.tile_h);
        if crate::stages::hiz::words(f.tile_w, f.tile_h) > capacity(pixels) {
            return Ok(None);
        }
        let mut passes = Vec::with_capacity(lv.len());
        for (k, l) in lv.iter().enumerate() {
            let below = if k == 0 { [0; 3] } else { lv[k - 1] };
            let params = HizParams {
                width: f.tile_w,
                height: f.tile_h,
                spp: f.spp_x * f.spp_y,
                tile_px: HIZ_TILE_PX,
                src_w: below[0],
                src_h: below[1],
                src_off: below[2],
                dst_off: l[2],
                dst_w: l[0],
                dst_h: l[1],
                pad: [0; 2],
            };
            let buf = gpu.upload("hiz params", &[params])?;
            let (pipeline, entries) = if k == 0 {
                (&self.level0, vec![(0, &buf), (1, samples), (2, hiz)])
            } else {
                (&self.reduce, vec![(0, &buf), (2, hiz)])
            };
            let bind =
                gpu.bind_buffers_at("reyes hiz", &pipeline.get_bind_group_layout(0), &entries);
            passes.push((k == 0, bind, [l[0].div_ceil(8), l[1].div_ceil(8)]));
        }
        Ok(Some(HizPasses { passes }))
    }

    /// Records `p` ([`HizPipelines::passes`]) into `enc`: one compute pass, a dispatch per
    /// level.
    pub(crate) fn record_passes(&self, enc: &mut wgpu::CommandEncoder, p: &HizPasses) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("reyes hiz"),
            timestamp_writes: None,
        });
        for (level0, bind, [gx, gy]) in &p.passes {
            pass.set_pipeline(if *level0 { &self.level0 } else { &self.reduce });
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(*gx, *gy, 1);
        }
    }
}

/// The pyramid's passes for one bucket, made by [`HizPipelines::passes`]: per level, whether
/// it is level 0, its bind group (which keeps its parameters alive) and its workgroups.
pub(crate) struct HizPasses {
    passes: Vec<(bool, wgpu::BindGroup, [u32; 2])>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `HizParams` has the size and offsets naga computes for hiz.wgsl's.
    #[test]
    fn hiz_params_match_the_wgsl_layout() {
        let l = scheduler::wgsl::struct_layout(crate::shaders::HIZ, "HizParams").unwrap();
        assert_eq!(l.size as usize, std::mem::size_of::<HizParams>());
        use std::mem::offset_of;
        for (field, off) in [
            ("spp", offset_of!(HizParams, spp)),
            ("tile_px", offset_of!(HizParams, tile_px)),
            ("src_off", offset_of!(HizParams, src_off)),
            ("dst_off", offset_of!(HizParams, dst_off)),
            ("dst_h", offset_of!(HizParams, dst_h)),
        ] {
            let got = l
                .members
                .iter()
                .find(|(n, _)| n == field)
                .map(|m| m.1 as usize);
            assert_eq!(got, Some(off), "HizParams.{field}");
        }
    }
}
