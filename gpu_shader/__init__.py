"""The GPU backend: a fragment shader generated from the scene, drawn headless with moderngl.

`generate` turns a scene into a readable GLSL program holding only what the scene uses;
`render` draws it through EGL and reads every buffer back into a `marchlab.Frame`.
"""
