{# Macros the raster pipeline's templates share (Jinja): imported, never filled in alone. #}
{# A section's banner, as the sphere tracer's generated programs have them. #}
{% macro banner(title) %}
// ---- {{ title }} {{ "-" * [4, 86 - title | length] | max }}
{% endmacro %}
{# The camera as glsl/camera.glsl's camera_ray reads it, from the uniforms that #}
{# gpu_shader/raster.py (_set_camera) sets; `size` and `half_height` are declared here unless #}
{# the program has them already (glsl/raster/mesh.frag declares both). #}
{% macro camera(declared=False) %}
// The camera, set per frame (gpu_shader/raster.py, _set_camera): the basis and the half
// extents tan(fov / 2) W / H and tan(fov / 2) computed in float64 on the CPU, under the
// names glsl/camera.glsl reads.
uniform vec3 eye;
uniform vec3 forward;
uniform vec3 right;
uniform vec3 up;
uniform float half_width;
{% if not declared %}
uniform float half_height;
uniform vec2 size;
{% endif %}
#define CAMERA_POSITION eye
#define CAMERA_FORWARD forward
#define CAMERA_RIGHT right
#define CAMERA_UP up
#define HALF_WIDTH half_width
#define HALF_HEIGHT half_height
#define IMAGE_WIDTH size.x
#define IMAGE_HEIGHT size.y
{% endmacro %}
