{# A template: gpu_shader/generate.py fills in the {{ }} parts (Jinja). #}
// The cone pre-pass's entry point as a compute shader (glsl/prepass.frag as a fragment
// shader): one invocation per tile of PREPASS_TILE x PREPASS_TILE pixels, storing its start
// into texel (i, j) of a ceil(W / T) x ceil(H / T) image, which glsl/main.comp then reads.

layout(local_size_x = GROUP_SIZE, local_size_y = GROUP_SIZE) in;

layout(r32f, binding = 0) uniform writeonly image2D out_start;
uniform ivec2 tiles;          // columns and rows of tiles

void main()
{
    load_parameters();
    ivec2 tile = ivec2(gl_GlobalInvocationID.xy);
    if (tile.x >= tiles.x || tile.y >= tiles.y) {
        return;
    }
    imageStore(out_start, tile, vec4(tile_start(real(tile.x), real(tile.y)), 0.0, 0.0, 0.0));
}
