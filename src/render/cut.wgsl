// Cut surfaces: each point coloured from the organ's interior solid
// texture (block_colour, from solid/sample_block.wgsl, or lst_colour, from
// solid/lst/sample.wgsl, both prepended to this file), lit like the
// facets.

struct CutIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct CutOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

@vertex
fn vs_cut(v: CutIn) -> CutOut {
    var out: CutOut;
    out.clip_position = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    return out;
}

// The block holds sRGB-encoded bytes read as they are (sample_block.wgsl);
// the target encodes linear light, so decode first.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_cut(in: CutOut) -> @location(0) vec4<f32> {
    return vec4<f32>(shade(srgb_to_linear(block_colour(in.world)), normalize(in.normal), in.world, cut_finish()), 1.0);
}

// Cuts through a lapped solid texture (sample.wgsl of solid::lst): each
// triangle lies in one tet, so the barycentric coordinates and depth
// interpolate exactly and the tet's slot is flat.
struct LstCutIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) bary: vec4<f32>,
    @location(3) depth: f32,
    @location(4) slot: u32,
}

struct LstCutOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) bary: vec4<f32>,
    @location(3) depth: f32,
    @location(4) @interpolate(flat) slot: u32,
}

@vertex
fn vs_lst_cut(v: LstCutIn) -> LstCutOut {
    var out: LstCutOut;
    out.clip_position = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.bary = v.bary;
    out.depth = v.depth;
    out.slot = v.slot;
    return out;
}

@fragment
fn fs_lst_cut(in: LstCutOut) -> @location(0) vec4<f32> {
    let c = lst_colour(in.slot, in.bary, in.depth);
    return vec4<f32>(shade(srgb_to_linear(c), normalize(in.normal), in.world, cut_finish()), 1.0);
}
