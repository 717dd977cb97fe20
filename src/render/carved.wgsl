// Faces a carving exposed (organtex::runtime::Carving): each textured
// from its page of the cut-texture atlas, whose texels are the interior's
// colours, lit like the facets and cuts.

@group(1) @binding(0) var page: texture_2d<f32>;
@group(1) @binding(1) var page_sampler: sampler;

struct CarvedIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct CarvedOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_carved(v: CarvedIn) -> CarvedOut {
    var out: CarvedOut;
    out.clip_position = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.uv = v.uv;
    return out;
}

@fragment
fn fs_carved(in: CarvedOut) -> @location(0) vec4<f32> {
    if clipped(in.world) {
        discard;
    }
    // The page is sRGB: sampling decodes it to linear light.
    let c = textureSampleLevel(page, page_sampler, in.uv, 0.0).rgb;
    return vec4<f32>(shade(c, normalize(in.normal), in.world, cut_finish()), 1.0);
}
