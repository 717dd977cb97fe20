// The solid texture of an organ's interior, for faces a cut exposes:
// include this in a fragment shader and call organtex_block_colour(coords)
// with the 3D texture coordinates the runtime gives per vertex
// (organtex_node_block_coordinates, in voxel units), interpolated.
//
// Host side (OpenGL 3.3+, GLSL ES 3.0, or Vulkan GLSL with a binding
// qualifier added), matching organtex's CPU colours:
// - organtex_block: the block as a 3D texture, GL_RGB8 (or RGBA8), voxel
//   (x, y, z) at texel (x, y, z), one mip level;
// - its sampler: GL_REPEAT on s, t and r (the block tiles space),
//   GL_LINEAR min and mag filters (trilinear between voxel centres).
// Colours come out in 0..1, the CPU's 0..255 divided by 255.

uniform sampler3D organtex_block;

// The block's colour at voxel-unit coordinates: normalised, voxel i's
// centre at (i + 0.5) / size, as the CPU samples. An explicit level so it
// also runs outside fragment shaders.
vec3 organtex_block_colour(vec3 coords) {
    vec3 size = vec3(textureSize(organtex_block, 0));
    return textureLod(organtex_block, coords / size, 0.0).rgb;
}
