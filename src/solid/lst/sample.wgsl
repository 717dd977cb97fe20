// Lapped solid textures on cut surfaces (seed 000, sec. 5.1), matching
// LstInterior::colour_in on the CPU: include this in a shader (as
// solid::lst::gpu::sample_lst_wgsl() gives it, the mask's constants
// prepended) and call lst_colour(slot, b, depth) with what a cut vertex
// carries.
//
// Host side (wgpu), filled by solid::lst::gpu::CutBuffers. The tables are
// 2D textures LST_ROW texels wide read with textureLoad, not storage
// buffers, so this runs where fragment shaders have none (GL ES 3.0,
// WebGL2, the viewer on wgpu's GL backend):
// - lst_exemplar: the exemplar as a 3D texture, Rgba8Unorm, one mip level,
//   voxel (x, y, z) at texel (x, y, z), sampled by lst_sampler with
//   address mode Repeat and Linear filters (as sample_block.wgsl);
// - lst_tets (Rgba32Uint): per tet the cut passes through (its slot), the
//   first of its layers, their count and its model's splotch;
// - lst_layers (Rgba32Float): per layer in paste order 4 texels, its
//   corners' texture coordinates in xyz, the mask kind in the first's w;
// - lst_waves (Rgba32Float): per splotch, 6 waves of 2 texels each
//   (direction times frequency and phase; amplitude).
// All in bind group 2, leaving group 0 to the including shader's camera
// and group 1 to the block sampler. Colours come out in 0..1.

@group(2) @binding(0) var lst_exemplar: texture_3d<f32>;
@group(2) @binding(1) var lst_sampler: sampler;
@group(2) @binding(2) var lst_tets: texture_2d<u32>;
@group(2) @binding(3) var lst_layers: texture_2d<f32>;
@group(2) @binding(4) var lst_waves: texture_2d<f32>;

// Where entry i of a table lies.
fn lst_texel(i: u32) -> vec2<i32> {
    return vec2<i32>(i32(i % LST_ROW), i32(i / LST_ROW));
}

// Smooth step from 1 (x <= 0) down to 0 (x >= 1).
fn lst_fall(x: f32) -> f32 {
    let t = clamp(x, 0.0, 1.0);
    return 1.0 - t * t * (3.0 - 2.0 * t);
}

// The splotch's radius towards unit direction d.
fn lst_radius(splotch: u32, d: vec3<f32>) -> f32 {
    var wander = 0.0;
    for (var k = 0u; k < 6u; k++) {
        let at = splotch * 12u + 2u * k;
        let wave = textureLoad(lst_waves, lst_texel(at), 0);
        wander += textureLoad(lst_waves, lst_texel(at + 1u), 0).x * cos(dot(wave.xyz, d) + wave.w);
    }
    return LST_RADIUS * (1.0 + LST_WANDER * wander);
}

// The mask's alpha at texture coordinates w (mask.rs, Splotch::alpha).
fn lst_alpha(mask: u32, splotch: u32, w: vec3<f32>) -> f32 {
    let c = w - vec3<f32>(0.5);
    let least = LST_RADIUS * (1.0 - LST_WANDER) - LST_FALLOFF;
    let most = LST_RADIUS * (1.0 + LST_WANDER);
    if mask == 0u {
        let r = length(c);
        if r <= least {
            return 1.0;
        }
        if r >= most {
            return 0.0;
        }
        let edge = lst_radius(splotch, c / r);
        return lst_fall((r - (edge - LST_FALLOFF)) / LST_FALLOFF);
    }
    let r = length(c.xz);
    if r >= most {
        return 0.0;
    }
    var lateral = 1.0;
    if r > least {
        let edge = lst_radius(splotch, vec3<f32>(c.x / r, 0.0, c.z / r));
        lateral = lst_fall((r - (edge - LST_FALLOFF)) / LST_FALLOFF);
    }
    let s = w.y;
    var depth: f32;
    if mask == 1u {
        depth = lst_fall((s - LST_BAND_OUTER) / LST_FALLOFF);
    } else if mask == 3u {
        depth = lst_fall((LST_BAND_INNER - s) / LST_FALLOFF);
    } else {
        depth = min(
            lst_fall((s - LST_BAND_MIDDLE_HI) / LST_FALLOFF),
            lst_fall((LST_BAND_MIDDLE_LO - s) / LST_FALLOFF),
        );
    }
    return lateral * depth;
}

// The colour in the tet at `slot`, barycentric coordinates b, where the
// depth (layered models) is `depth`: its layers composited in paste order
// and divided by their total alpha; the first layer where none reaches.
fn lst_colour(slot: u32, b: vec4<f32>, depth: f32) -> vec3<f32> {
    let tet = textureLoad(lst_tets, lst_texel(slot), 0);
    let size = vec3<f32>(textureDimensions(lst_exemplar));
    var out = vec3<f32>(0.0);
    var clear = 1.0;
    var first = vec3<f32>(0.0);
    for (var k = 0u; k < tet.y; k++) {
        let at = 4u * (tet.x + k);
        let c0 = textureLoad(lst_layers, lst_texel(at), 0);
        let c1 = textureLoad(lst_layers, lst_texel(at + 1u), 0);
        let c2 = textureLoad(lst_layers, lst_texel(at + 2u), 0);
        let c3 = textureLoad(lst_layers, lst_texel(at + 3u), 0);
        var w = b.x * c0.xyz + b.y * c1.xyz + b.z * c2.xyz + b.w * c3.xyz;
        let mask = u32(c0.w);
        // A depth band's patch is layered: s is the depth, the exemplar's
        // y clamped rather than wrapped.
        var voxel = w * size;
        if mask != 0u {
            w.y = depth;
            voxel = vec3<f32>(voxel.x, clamp(depth * size.y, 0.5, size.y - 0.5), voxel.z);
        }
        let c = textureSampleLevel(lst_exemplar, lst_sampler, voxel / size, 0.0).rgb;
        if k == 0u {
            first = c;
        }
        let alpha = lst_alpha(mask, tet.z, w);
        out = out * (1.0 - alpha) + c * alpha;
        clear *= 1.0 - alpha;
    }
    let covered = 1.0 - clear;
    if covered > 1e-4 {
        return out / covered;
    }
    return first;
}
