{# A template: gpu_shader/generate.py fills in the {{ }} parts (Jinja). #}
// The cone pre-pass's entry point: one invocation per tile of PREPASS_TILE x PREPASS_TILE
// pixels, drawn into a texture of ceil(W / T) x ceil(H / T) texels before the frame
// (gpu_shader/render.py). Texel (i, j) is tile column i, tile row j counted from the top,
// as main.frag reads it.

layout(location = 0) out float out_start;

void main()
{
    load_parameters();
    // gl_FragCoord is the texel's centre (i + 0.5, j + 0.5): floor gives the tile's index.
    out_start = tile_start(floor(gl_FragCoord.x), floor(gl_FragCoord.y));
}
