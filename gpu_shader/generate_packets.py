"""The packet form of the OpenCL program: the same pipeline over LANES rays at once.

`gpu_shader.generate` writes a program that traces one ray per work-item. On a CPU that
leaves the SIMD units idle, because PoCL does not vectorise a kernel whose loop trip count
depends on the data (docs/performance.md). The packet program gives each
work-item LANES neighbouring pixels of a row and computes on vectors with one lane per ray
(glsl/packet.cl). Most of it comes from where the one-ray program comes from:

- the building blocks are twins of the scalar ones, with the same names
  (``glsl/<name>_packet.cl`` for ``glsl/<name>.glsl``, `Dialect.library`);
- the scene's SDF, object ids and culling come from the same writer with packet types
  (`gpu_shader.sdf_code.PACKET_TYPES`);
- the parameter block, the march and shadow selection and the light parameters are those of
  `gpu_shader.generate`.

This module writes the parts that read differently over packets: the normal (vector
arithmetic as calls), materials (gathered lane by lane, since each ray may have hit another
object), the shading sum over the lights and the per-pixel pipeline, where the one-ray
program's branches (did this ray hit? does it bounce again?) become masks.
"""

from __future__ import annotations

from reference_cpu.normals import STENCILS
from scene_model.colormaps import HEAT_COLORS, HEAT_STOPS

from .generate import _Generator


class PacketGenerator(_Generator):
    """`gpu_shader.generate._Generator` for a packet dialect."""

    def normal_code(self) -> str:
        """``estimate_normal`` for the chosen stencil, over a packet of points."""
        method = self.s.normal_method
        self.features.add(f"normals:{method}")
        lines = [f"// Normal by finite differences, the {method!r} stencil of reference_cpu/normals.py:",
                 "// n = normalize(sum_k k scene_sdf(p + h k)); zero where the gradient vanishes.",
                 "vec3p estimate_normal(vec3p p)", "{", "    real h = NORMAL_STEP;",
                 "    vec3p g = splat3(vec3(0.0));"]
        for k in STENCILS[method]:
            k = ", ".join(self.d.literal(c) for c in k)
            lines.append(f"    g = add(g, mul(scene_sdf(add(p, h * vec3({k}))), vec3({k})));")
        lines += ["    packet size = sqrt(dot(g, g));",
                  "    return choose(size > 0.0, div(g, size), splat3(vec3(0.0)));", "}", ""]
        return "\n".join(lines)

    def material_code(self) -> str:
        """Material rows per object id, gathered per lane, and (with checkers)
        ``surface_albedo`` and ``surface_checker_parity`` over the gathered rows."""
        first, stride, rows = self.material_rows()
        lines = [
            rows,
            "// Row `row` of the material of each lane's object: a gather, one load per lane.",
            "// Lanes whose ray hit nothing (id -1) read object 0's row and never use it.",
            "vec4p material(ipacket id, int row)", "{",
            "    real x[LANES], y[LANES], z[LANES], w[LANES];",
            "    for (int k = 0; k < LANES; k++) {",
            f"        vec4 m = U[{first} + {stride} * max((int)(id[k]), 0) + row];",
            "        x[k] = m.x;",
            "        y[k] = m.y;",
            "        z[k] = m.z;",
            "        w[k] = m.w;",
            "    }",
            "    vec3p xyz = pack3(vload_packet(0, x), vload_packet(0, y), vload_packet(0, z));",
            "    return pack4(xyz, vload_packet(0, w));",
            "}", ""]
        if self.checker:
            # shade_* gathers each row once and passes the rows on.
            lines += ["vec3p surface_albedo(vec3p p, vec4p row0, vec4p row2, vec4p row3)", "{",
                      "    return choose(row3.w > 0.0, checker(p, row2.xyz, row3.xyz, row2.w), row0.xyz);",
                      "}", "",
                      "packet surface_checker_parity(vec3p p, vec4p row2, vec4p row3)", "{",
                      "    return row3.w > 0.0 ? checker_parity(p, row2.w) : (packet)(0.0);",
                      "}", ""]
        return "\n".join(lines)

    def light_code(self) -> tuple[str, list[str]]:
        """The shading function over a packet: the lights' terms, shadows for the lanes in
        ``live`` only."""
        mode, needs = self.s.shading, set()
        term, spec = self.light_terms()
        lines = [f"// The {mode} model (reference_cpu/shading.py) summed over the lights, plus ambient,",
                 "// for the lanes in `live`. Returns (colour, features): features codes the checker",
                 "// cell and, one bit per light, whether a hard shadow blocked it (for the path label).",
                 f"vec4p shade_{mode}(vec3p p, vec3p n, vec3p v, ipacket id, ipacket live)", "{",
                 "    vec4p row0 = material(id, 0);",
                 "    vec4p row1 = material(id, 1);"]
        if self.checker:
            lines += ["    vec4p row2 = material(id, 2);",
                      "    vec4p row3 = material(id, 3);",
                      "    vec3p albedo = surface_albedo(p, row0, row2, row3);"]
        else:
            lines += ["    vec3p albedo = row0.xyz;"]
        lines += ["    packet ka = row0.w;",
                  "    packet kd = row1.xyz.x;",
                 "    packet ks = row1.xyz.y;",
                 "    packet shininess = row1.xyz.z;",
                 "    vec3p color = mul(mul(ka, albedo), AMBIENT);",
                 "    packet features = "
                 + ("surface_checker_parity(p, row2, row3);" if self.checker else "0.0;"),
                 "    packet visible;",
                 "    LightSample s;"]
        for i, light in enumerate(self.scene.lights):
            kind, call = self.light_call(i, light)
            needs.add(f"light_{kind}")
            lines += [f"    // light {i}: {kind}", f"    s = {call};"]
            if self.s.shadows != "none":
                lines.append("    visible = light_visible(p, n, s, live);")
                lines.append("    s.radiance = mul(visible, s.radiance);")
                blocked = ("(visible == 0.0 ? (packet)(1.0) : (packet)(0.0))"
                           if self.s.shadows == "hard" else "0.0")
                lines.append(f"    features = 2.0 * features + {blocked};")
            else:
                lines.append("    features = 2.0 * features;")
            lines.append(f"    color = add(color, mul(s.radiance, add(mul(kd * {term}, albedo), "
                         f"ks * {spec})));")
        lines += ["    return pack4(color, features);", "}", ""]
        source = "\n".join(lines)
        if self.s.shadows != "none" and self.scene.lights:
            source = self.shadow_code() + "\n" + source
        return source, sorted(needs)

    def shadow_code(self) -> str:
        return "\n".join([
            "// How much of light s reaches p, in the lanes of `live` (1 elsewhere): shadow rays",
            "// start SURFACE_OFFSET off the surface (else they find the surface itself: shadow",
            "// acne), and only where the surface faces a light that sends something.",
            "packet light_visible(vec3p p, vec3p n, LightSample s, ipacket live)",
            "{",
            "    ipacket lit = dot(n, s.to_light) > 0.0"
            " && max(s.radiance.x, max(s.radiance.y, s.radiance.z)) > 0.0;",
            "    vec3p origin = add(p, mul(SURFACE_OFFSET, n));",
            f"    return {self.s.shadows}_shadow(origin, s.to_light, s.distance, live & lit);",
            "}", ""])

    def heat_code(self) -> str:
        """``heat`` over a packet: each lane takes the segment of the ramp its value is in,
        tried from the last segment back to the first."""
        lit = self.d.literal
        lines = ["// The heat ramp of scene_model/colormaps.py: linear between its stops.",
                 "vec3p heat(packet x)", "{", "    x = clamp(x, 0.0, 1.0);",
                 "    vec3p color;"]
        last = len(HEAT_STOPS) - 2
        for i in reversed(range(last + 1)):
            x0, x1 = HEAT_STOPS[i], HEAT_STOPS[i + 1]
            c0 = ", ".join(lit(c) for c in HEAT_COLORS[i])
            c1 = ", ".join(lit(c) for c in HEAT_COLORS[i + 1])
            segment = (f"add(mul((x - {lit(x0)}) / {lit(x1 - x0)}, vec3({c1}) - vec3({c0})), "
                       f"vec3({c0}))")
            if i == last:
                lines.append(f"    color = {segment};")
            else:
                lines.append(f"    color = choose(x <= {lit(x1)}, {segment}, color);")
        lines += ["    return color;", "}", ""]
        return "\n".join(lines)

    def pixel_code(self) -> str:
        mode = self.s.shading
        head = ["// The colour and path label of each pixel of the packet, given its primary ray,",
                "// the march result h and, where it hit, the normal n and object id there",
                "// (reference_cpu/render.py, Tracer.trace).",
                "vec4p pixel_color(vec3p origin, vec3p direction, Hit h, vec3p n, ipacket id)", "{"]
        path = "path_step(0u, id, 0u)"
        if mode == "steps":
            path = "path_step(convert_upacket(h.steps), id, 0u)"
            color = "heat(convert_packet(h.steps) / (real)(MAX_STEPS))"
        elif mode == "normals":
            color = "choose(h.hit, shade_normals(n), background(direction))"
        elif mode == "depth":
            color = "choose(h.hit, shade_depth(h.t, MAX_DISTANCE), background(direction))"
        else:
            return self.lit_pixel_code(head)
        return "\n".join(head + [f"    return pack4({color}, convert_packet({path}));", "}", ""])

    def lit_pixel_code(self, head: list[str]) -> str:
        """Shading, fog and the reflection loop, with masks for the lanes still going."""
        shade = f"shade_{self.s.shading}(p, n, neg(d), id, {{live}})"
        fog = ["shaded = apply_fog(shaded, h.t, FOG_COLOR, FOG_DENSITY);"] if self.fog else []
        if not self.reflections:
            return "\n".join(head + [
                "    vec3p d = direction;",
                "    vec3p p = add(origin, mul(h.t, d));",
                f"    vec4p lit = {shade.format(live='h.hit')};",
                "    vec3p shaded = lit.xyz;"] + [f"    {f}" for f in fog] + [
                "    upacket path = h.hit ? path_step(0u, id, convert_upacket(lit.w)) "
                ": path_step(0u, -1, 0u);",
                "    return pack4(choose(h.hit, shaded, background(direction)), "
                "convert_packet(path));", "}", ""])
        self.features.add("reflections")
        lines = head + [
            "    // Each bounce adds its shaded colour weighted by the product of the kr seen",
            "    // so far; a ray that hits nothing adds the background. `going` holds the lanes",
            "    // whose ray is still bouncing.",
            "    vec3p color = splat3(vec3(0.0));",
            "    upacket path = 0u;",
            "    packet weight = 1.0;",
            "    vec3p o = origin;",
            "    vec3p d = direction;",
            "    ipacket going = -1;",
            "    for (int bounce = 0; bounce <= REFLECTION_DEPTH; bounce++) {",
            "        if (bounce > 0) {",
            "            h = march(o, d, MAX_DISTANCE, going);",
            "        }",
            "        ipacket missed = going & ~h.hit;",
            "        color = choose(missed, add(color, mul(weight, background(d))), color);",
            "        path = missed ? path_step(path, -1, 0u) : path;",
            "        going = going & h.hit;",
            "        if (!any(going)) {",
            "            break;",
            "        }",
            "        vec3p p = add(o, mul(h.t, d));",
            "        if (bounce > 0) {",
            "            n = choose(going, estimate_normal(p), n);",
            "            id = going ? scene_object_id(p) : id;",
            "        }",
            f"        vec4p lit = {shade.format(live='going')};",
            "        vec3p shaded = lit.xyz;"] + [f"        {f}" for f in fog] + [
            "        color = choose(going, add(color, mul(weight, shaded)), color);",
            "        path = going ? path_step(path, id, convert_upacket(lit.w)) : path;",
            "        weight = going ? weight * material(id, 1).w : weight;",
            "        going = going & (weight > 0.0);",
            "        if (bounce == REFLECTION_DEPTH || !any(going)) {",
            "            break;",
            "        }",
            "        // Continue just off the mirror, in the mirrored direction.",
            "        o = choose(going, add(p, mul(SURFACE_OFFSET, n)), o);",
            "        d = choose(going, reflect(d, n), d);",
            "    }",
            "    return pack4(color, convert_packet(path));", "}", ""]
        return "\n".join(lines)
