// What every pass shares, prepended to each shader: the frame's globals
// (group 0), the cut plane's test and the light: the endoscope's, at the
// scope's tip, or an even light for judging textures alone.

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: the eye; w: a typical depth, for the light's falloff.
    eye: vec4<f32>,
    // xyz: the cut plane's normal, w: its offset; points with
    // dot(n, p) > w are cut away. A zero normal cuts nothing.
    clip: vec4<f32>,
    // x: bump on (1) or off (0); y: heat map (1) or texture (0);
    // z: endoscope light (1) or even light (0); w: exposure.
    flags: vec4<f32>,
    // xyz: where the scope looks (unit); w: the cosine of its light
    // cone's half angle, past which no light falls.
    scope: vec4<f32>,
}

@group(0) @binding(0) var<uniform> globals: Globals;

fn clipped(p: vec3<f32>) -> bool {
    return dot(globals.clip.xyz, globals.clip.xyz) > 0.0 && dot(globals.clip.xyz, p) > globals.clip.w;
}

// The even light: at the eye, two-sided, fading gently with distance.
fn headlamp(n: vec3<f32>, p: vec3<f32>) -> f32 {
    let to_eye = globals.eye.xyz - p;
    let d = length(to_eye);
    let falloff = 1.0 / (1.0 + pow(d / (1.5 * globals.eye.w), 2.0));
    return (0.15 + 0.85 * abs(dot(n, to_eye / max(d, 1e-20)))) * (0.4 + 1.2 * falloff);
}

// How a surface takes the endoscope's light: the tissue's own roughness,
// and a clear coat (the mucus film) of some weight and roughness.
struct Finish {
    roughness: f32,
    coat: f32,
    coat_roughness: f32,
}

const PI: f32 = 3.14159265;

// The radius of the scope's light, the ring of fibres round a
// hysteroscope's lens, as a fraction of the view's typical depth (the
// camera's distance to what it looks at): 1.5 mm at 36 mm.
const SCOPE_LIGHT_RADIUS: f32 = 0.04;

// GGX (Trowbridge-Reitz) specular lobe times Smith's masking, for light
// and view from one point (the scope's light sits at its lens, so the
// half vector is the view direction): D G / (4 n.l n.v) with n.l = n.v.
fn ggx_at_eye(cos_n: f32, roughness: f32) -> f32 {
    let a = max(roughness * roughness, 2e-3);
    let a2 = a * a;
    let c2 = cos_n * cos_n;
    let den = c2 * (a2 - 1.0) + 1.0;
    let d = a2 / (PI * den * den);
    let g1 = 2.0 * cos_n / (cos_n + sqrt(a2 + (1.0 - a2) * c2));
    return d * g1 * g1 / max(4.0 * c2, 1e-4);
}

// Filmic tone curve (Narkowicz's fit of ACES), so that highlights
// saturate and the near wall does not clip flat.
fn tone_curve(x: f32) -> f32 {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

// The tone curve on the brightest channel, the others scaled with it: a
// bright near wall keeps the tissue's hue instead of fading to white
// channel by channel; only where the film's white reflection dominates
// does a pixel go white.
fn tone_map(x: vec3<f32>) -> vec3<f32> {
    let peak = max(max(x.r, x.g), max(x.b, 1e-6));
    return x * (tone_curve(peak) / peak);
}

// Linear colour of a surface of linear `albedo` at `p` with unit normal
// `n` (two-sided), as the frame's light shows it. Endoscope: a spot light
// at the scope's tip along its axis, falling off with the square of the
// distance; Lambertian tissue under a clear coat whose Fresnel
// reflectance at normal incidence is 0.02 (water, n = 1.33), the light
// the coat reflects lost to the tissue below. Even: `headlamp`.
fn shade(albedo: vec3<f32>, n: vec3<f32>, p: vec3<f32>, finish: Finish) -> vec3<f32> {
    return shade_wet(albedo, n, n, p, finish);
}

// `shade` with the fine relief seen twice: the film on top follows it
// sharply (`n_film`), while the tissue's diffuse light, scattered under
// the surface before it leaves, shows it softened (`n_tissue`), as
// renderers of skin soften the normal map for the diffuse term (d'Eon and
// Luebke, GPU Gems 3, ch. 14). The even light takes the tissue's.
fn shade_wet(albedo: vec3<f32>, n_tissue: vec3<f32>, n_film: vec3<f32>, p: vec3<f32>, finish: Finish) -> vec3<f32> {
    if globals.flags.z < 0.5 {
        return albedo * headlamp(n_tissue, p);
    }
    let to_eye = globals.eye.xyz - p;
    let d = max(length(to_eye), 1e-6);
    let l = to_eye / d;
    // Both normals turned to the eye by the side the tissue's (the
    // smoother) normal faces: where the relief tilts the film's normal
    // past the horizon, that facet faces away, it is not the back face.
    let side = select(1.0, -1.0, dot(n_tissue, l) < 0.0);
    let cos_n = max(side * dot(n_film, l), 0.0);
    let cos_t = max(side * dot(n_tissue, l), 0.0);
    // The cone (draw::scope_cone): full inside the inner angle, whose
    // cosine is halfway from the outer's to 1, none past the outer.
    let off_axis = dot(-l, globals.scope.xyz);
    let cone = smoothstep(globals.scope.w, mix(globals.scope.w, 1.0, 0.5), off_axis);
    // Irradiance normalised so a surface facing the scope at a quarter of
    // the typical depth gets the exposure.
    let r = globals.eye.w / 4.0;
    let irradiance = globals.flags.w * cone * r * r / (d * d);
    let f0 = 0.02;
    // The lobe's width (GGX alpha squared) from three sources: the coat's
    // roughness; specular anti-aliasing, where the normal turns within a
    // pixel (alpha^2 grows by that turn's variance, so a glint smaller than
    // a pixel is not a lone sparkling dot); and the light's own size, its
    // fibre bundle seen from the surface, which widens a sharp reflection
    // into the bundle's image at the same energy (Karis 2013, sphere
    // lights: alpha grows by the source's radius over twice the distance).
    let dn = fwidth(n_film);
    let widen = min(0.25 * dot(dn, dn), 0.002);
    let source = SCOPE_LIGHT_RADIUS * globals.eye.w / (2.0 * d);
    let coat_roughness = sqrt(sqrt(pow(finish.coat_roughness, 4.0) + widen + source * source));
    // Specular radiance is the BRDF times the irradiance; the diffuse
    // term below is albedo times irradiance (the Lambertian 1/pi folded
    // into the exposure, as the .glb's light intensity shows), so the
    // lobes take the pi back.
    let coat = PI * finish.coat * f0 * ggx_at_eye(cos_n, coat_roughness);
    let sheen = PI * 0.04 * ggx_at_eye(cos_n, finish.roughness);
    // Light scattered under the surface reaches a little past the
    // terminator (wrapped diffuse), so crevices turned from the scope are
    // dim, not black.
    let wrapped = (cos_t + 0.3) / 1.3;
    let diffuse = albedo * (1.0 - finish.coat * f0) * wrapped;
    // A little light scattered round the cavity, so nothing is pure black.
    let ambient = 0.02 * globals.flags.w * albedo;
    let tissue = irradiance * diffuse + ambient;
    let film = irradiance * cos_n * (coat + sheen);
    // The film's reflection is white light over the tissue's colour: it
    // goes on top (screen), so a glint is white however pink the tissue.
    let under = tone_map(tissue);
    return under + (1.0 - under) * tone_curve(film);
}

// Cut and carved faces: fresh tissue, wet but without the mucus film.
fn cut_finish() -> Finish {
    return Finish(0.55, 0.5, 0.25);
}
