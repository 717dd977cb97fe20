// The solid texture of an organ's interior, for cut surfaces: include this
// in a shader and call block_colour(p) with an object-space position.
//
// Host side (wgpu), matching organtex::solid::cut on the CPU:
// - block: the voxel block as a 3D texture, Rgba8Unorm, one mip level,
//   voxel (x, y, z) at texel (x, y, z);
// - block_sampler: address modes Repeat on u, v and w (the block tiles
//   space), mag and min filters Linear (trilinear between voxel centres);
// - placement: Placement::uniform(), 16 bytes: origin x, y, z, scale.
// All three in bind group 1, leaving group 0 to the including shader's
// camera and model.
// Colours come out in 0..1, the CPU's 0..255 divided by 255.

struct BlockPlacement {
    // Object-space position of the block's corner.
    origin: vec3<f32>,
    // Object units one voxel spans.
    scale: f32,
}

@group(1) @binding(0) var block: texture_3d<f32>;
@group(1) @binding(1) var block_sampler: sampler;
@group(1) @binding(2) var<uniform> placement: BlockPlacement;

// Voxel coordinates of an object-space point, as texture_coordinates()
// gives them.
fn block_coordinates(p: vec3<f32>) -> vec3<f32> {
    return (p - placement.origin) / placement.scale;
}

// The block's colour at 3D texture coordinates in voxel units (what
// organtex's runtime gives per vertex, interpolated). Normalised
// coordinates put voxel i's centre at (i + 0.5) / size, as Volume::sample
// does in voxel units.
fn block_colour_at(coords: vec3<f32>) -> vec3<f32> {
    let size = vec3<f32>(textureDimensions(block));
    return textureSampleLevel(block, block_sampler, coords / size, 0.0).rgb;
}

// The block's colour at an object-space point. Normalised coordinates put
// voxel i's centre at (i + 0.5) / size, as Volume::sample does in voxel
// units. An explicit level so it also runs outside fragment shaders.
fn block_colour(p: vec3<f32>) -> vec3<f32> {
    return block_colour_at(block_coordinates(p));
}
