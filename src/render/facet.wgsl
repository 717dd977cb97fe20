// Textured facets, as the .glb draws them (scene::draw): the tissue
// texture through the material's texture transform (KHR_texture_transform),
// tangent-space bump from the normal map, blend weight per vertex, lit by
// the scope's light as an endoscope lights what it sees (frame.wgsl's
// shade_wet, prepended with the globals), the wet film glinting where its
// relief faces the scope. Also the distortion heat map and the
// wireframe and seam lines, from the same vertices.

struct Material {
    // The texture transform as two rows of a 2x3 matrix; row0.w is 1 where
    // the texture is a tissue tiled through it, 0 for an atlas.
    row0: vec4<f32>,
    row1: vec4<f32>,
    factor: vec4<f32>,
    // x: bump strength (0: no normal map); the tissue's finish: y its
    // roughness, z its clear coat's weight, w the coat's roughness.
    normal: vec4<f32>,
}

@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var colour_texture: texture_2d<f32>;
@group(1) @binding(2) var colour_sampler: sampler;
@group(1) @binding(3) var normal_texture: texture_2d<f32>;
@group(1) @binding(4) var normal_sampler: sampler;

// Where a carving tool took tissue away: a mask over a box of the scene,
// 1 inside the carved space. The facets are not drawn there, so the faces
// the carving exposed (drawn by carved.wgsl) show.
struct Carve {
    // xyz: the mask's corner; w: the object units a voxel spans.
    origin: vec4<f32>,
    // x: a mask is set (1) or not (0).
    flags: vec4<f32>,
}

@group(2) @binding(0) var carve_mask: texture_3d<f32>;
@group(2) @binding(1) var carve_sampler: sampler;
@group(2) @binding(2) var<uniform> carve: Carve;

// The mucus film is not even: it pools in some places and thins to a
// trace in others, so real frames glint in clusters of many sizes, with
// stretches of wall between them that hardly glint at all. The film's
// thickness here is a smooth random field over the surface (value noise),
// fixed in the tissue so it does not swim as the scope moves, its
// patches WET_PATCH of the facet's texture tile across (3.2 mm on the
// default wall's 16 mm tiles, 0.8 mm on the polyp's 4 mm), so the field
// scales with the scene (an overlay's layer by its own tile, so a vessel
// may glint where the tissue under it does not). It is taken per vertex,
// which the patches span several of on the bundled scenes; a mesh
// coarser than its tissue's tile would alias it. Where the film pools it
// is thick and levels the relief (its glints fewer and broader); where it
// thins the coat fades to 3%. An atlas, laid out once rather than tiled,
// has no tile to scale by and keeps an even film, as the .glb's clear
// coat does everywhere (glTF has no such field short of a texture per
// facet).
const WET_PATCH: f32 = 0.2;

fn lattice(i: vec3<i32>) -> f32 {
    var h = (u32(i.x) * 0x8da6b343u) ^ (u32(i.y) * 0xd8163841u) ^ (u32(i.z) * 0xcb1ab31fu);
    h = (h ^ (h >> 15u)) * 0x2c1b3c6du;
    h = (h ^ (h >> 12u)) * 0x297a2d39u;
    return f32(h >> 8u) / 16777216.0;
}

fn value_noise(p: vec3<f32>) -> f32 {
    let i = vec3<i32>(floor(p));
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    var corners: array<f32, 8>;
    for (var k = 0; k < 8; k++) {
        corners[k] = lattice(i + vec3<i32>(k & 1, (k >> 1) & 1, k >> 2));
    }
    let x00 = mix(corners[0], corners[1], u.x);
    let x10 = mix(corners[2], corners[3], u.x);
    let x01 = mix(corners[4], corners[5], u.x);
    let x11 = mix(corners[6], corners[7], u.x);
    return mix(mix(x00, x10, u.y), mix(x01, x11, u.y), u.z);
}

// 0 where the film is a trace, 1 where it pools.
fn wetness(p: vec3<f32>) -> f32 {
    if material.row0.w < 0.5 {
        return 1.0;
    }
    // The texture transform's first row is the tile's reciprocal.
    let tile = 1.0 / max(length(material.row0.xy), 1e-6);
    return smoothstep(0.45, 0.75, value_noise(p / (WET_PATCH * tile)));
}

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) alpha: f32,
    @location(4) tangent: vec4<f32>,
    @location(5) heat: f32,
}

struct VertexOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) alpha: f32,
    @location(4) tangent: vec4<f32>,
    @location(5) heat: f32,
    @location(6) wet: f32,
}

fn vertex(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip_position = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    let t = vec3<f32>(v.uv, 1.0);
    out.uv = vec2<f32>(dot(material.row0.xyz, t), dot(material.row1.xyz, t));
    out.alpha = v.alpha;
    out.tangent = v.tangent;
    out.heat = v.heat;
    out.wet = wetness(v.position);
    return out;
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    return vertex(v);
}

fn carved(p: vec3<f32>) -> bool {
    if carve.flags.x < 0.5 {
        return false;
    }
    let c = (p - carve.origin.xyz) / carve.origin.w / vec3<f32>(textureDimensions(carve_mask));
    if any(c < vec3<f32>(0.0)) || any(c > vec3<f32>(1.0)) {
        return false;
    }
    return textureSampleLevel(carve_mask, carve_sampler, c, 0.0).r > 0.5;
}

fn hidden(p: vec3<f32>) -> bool {
    return clipped(p) || carved(p);
}

// Blue (texture squeezed) through white to red (stretched), saturating at
// a factor of 2 in area.
fn heat_colour(h: f32) -> vec3<f32> {
    let t = clamp(h / log(2.0), -1.0, 1.0);
    if t < 0.0 {
        return mix(vec3<f32>(1.0), vec3<f32>(0.05, 0.2, 1.0), -t);
    }
    return mix(vec3<f32>(1.0), vec3<f32>(1.0, 0.1, 0.05), t);
}

// FILM_RELIEF (scene::draw::FILM_RELIEF) is prepended with the globals.
const FILM_LEVELS: f32 = 2.5;
// Where the film pools it levels the relief this many mip levels more,
// and flattens what is left of it to POOL_RELIEF of the thin film's: a
// pool is a smooth lens over the tissue, so a smooth dome (a polyp's head)
// glints once at the point that faces the scope, where the thin film's
// relief would spread that glint into a dull sheen (on the default
// preview, with FILM_RELIEF 8: 21 glints on 0.31% of the pixels, against
// 43 on 0.47% with neither; real frames: 1 to 29, median 3).
const POOL_LEVELS: f32 = 2.0;
const POOL_RELIEF: f32 = 0.25;

// The scope's depth of field. A hysteroscope's lens is fixed-focus, set
// for the wall a few millimetres from its tip, and its small sensor
// resolves less the farther the tissue: past the focus the blur circle
// grows as 1 - focus / distance (thin lens, far side), so the far cavity
// is soft and featureless as in real frames, not sharp to the fundus.
// The blur is taken as a coarser mip level of the textures, DEFOCUS_LEVELS
// levels at infinity (a blur of about 2^levels screen pixels where the
// texture is minified; none where it is magnified past that);
// the focus is SCOPE_FOCUS of the view's typical depth (9 mm at 36 mm).
// The even light, for judging textures, keeps them sharp.
const SCOPE_FOCUS: f32 = 0.25;
const DEFOCUS_LEVELS: f32 = 3.0;

fn defocus(p: vec3<f32>) -> f32 {
    if globals.flags.z < 0.5 {
        return 0.0;
    }
    let d = max(length(globals.eye.xyz - p), 1e-6);
    return DEFOCUS_LEVELS * max(1.0 - SCOPE_FOCUS * globals.eye.w / d, 0.0);
}

// How much of the relief the tissue's diffuse light shows where the
// surface is seen at `p` with macro normal `n`. Seen edge-on, a relief's
// slopes that face away are hidden behind those that face the scope and
// the light (at the scope) grazes them all alike, so real walls at a
// grazing angle look smooth; a normal map has no such masking and its
// bumps, lit at a grazing angle where the light changes fastest with the
// normal, drew the cavity's rim as dark streaks along it, which blind
// judges took for a stretched texture. The relief fades out from
// GRAZING_FULL to GRAZING_NONE (cosines of the view to the normal). The
// wet film keeps its relief: real rims glint. The even light keeps the
// old look.
const GRAZING_FULL: f32 = 0.5;
const GRAZING_NONE: f32 = 0.1;

fn relief_seen(n: vec3<f32>, p: vec3<f32>) -> f32 {
    if globals.flags.z < 0.5 {
        return 1.0;
    }
    let facing = abs(dot(n, normalize(globals.eye.xyz - p)));
    return smoothstep(GRAZING_NONE, GRAZING_FULL, facing);
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    if hidden(in.world) {
        discard;
    }
    var n = normalize(in.normal);
    var n_film = n;
    var finish = Finish(material.normal.y, material.normal.z, material.normal.w);
    let blur = defocus(in.world);
    let wet = in.wet;
    finish.coat = finish.coat * mix(0.03, 1.0, wet);
    if globals.flags.x > 0.5 && material.normal.x > 0.0 {
        let t = normalize(in.tangent.xyz - n * dot(n, in.tangent.xyz));
        let b = cross(n, t) * in.tangent.w;
        let m = textureSampleBias(normal_texture, normal_sampler, in.uv, blur).xyz * 2.0 - 1.0;
        let bump = material.normal.x;
        let tbn = mat3x3<f32>(t, b, n);
        // The film levels the relief finer than a few texels (surface
        // tension fills the pits): it reads the normal map FILM_LEVELS mip
        // levels coarser, so its glints are a few broad wet patches where
        // the relief faces the scope, as in real frames, not a sparkle on
        // every bump.
        let mf = textureSampleBias(normal_texture, normal_sampler, in.uv, FILM_LEVELS + POOL_LEVELS * wet + blur).xyz * 2.0 - 1.0;
        let film_relief = bump * FILM_RELIEF * mix(1.0, POOL_RELIEF, wet);
        n_film = normalize(tbn * vec3<f32>(mf.xy * film_relief, mf.z));
        n = normalize(tbn * vec3<f32>(m.xy * bump * relief_seen(n, in.world), m.z));
        // Where the relief varies within a texel of the mip level sampled,
        // the averaged normal is shorter: its variance widens the film's
        // lobe (Toksvig 2005), so distant relief glistens as a sheen, not
        // as sparkling dots.
        let len = length(mf);
        let variance = pow(film_relief, 2.0) * max(1.0 - len, 0.0) / max(len, 1e-3);
        finish.coat_roughness = sqrt(sqrt(pow(finish.coat_roughness, 4.0) + variance));
    }
    if globals.flags.y > 0.5 {
        return vec4<f32>(heat_colour(in.heat) * headlamp(n, in.world), 1.0);
    }
    let c = textureSampleBias(colour_texture, colour_sampler, in.uv, blur) * material.factor;
    return vec4<f32>(shade_wet(c.rgb, n, n_film, in.world, finish), c.a * in.alpha);
}

// Lines sit a little towards the eye so the faces they border do not hide
// them.
@vertex
fn vs_line(v: VertexIn) -> VertexOut {
    var out = vertex(v);
    out.clip_position.z = out.clip_position.z - 2e-4 * out.clip_position.w;
    return out;
}

@fragment
fn fs_wire(in: VertexOut) -> @location(0) vec4<f32> {
    if hidden(in.world) {
        discard;
    }
    return vec4<f32>(0.02, 0.02, 0.03, 1.0);
}

@fragment
fn fs_seam(in: VertexOut) -> @location(0) vec4<f32> {
    if hidden(in.world) {
        discard;
    }
    return vec4<f32>(1.0, 0.85, 0.0, 1.0);
}
