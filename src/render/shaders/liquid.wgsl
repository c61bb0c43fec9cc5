// The liquid surface: turns the splatted field (r: particle field, 1 inside a fluid at rest;
// g: field × speed; b: field × colour-map position; a: field × liquid rank) into a body with an anti-aliased edge where
// the field crosses the threshold, a colour that deepens with the liquid above, a lighter rim
// along the surface and foam where the flow is fast.

#import bevy_sprite::{
    mesh2d_vertex_output::VertexOutput,
    mesh2d_view_bindings::view,
}
#ifdef SRGB_OUTPUT
#import bevy_render::color_operations::linear_to_srgb
#endif

struct Liquid {
    shallow: vec4<f32>,
    deep: vec4<f32>,
    rim: vec4<f32>,
    foam: vec4<f32>,
    // x: threshold, y: rim width (px), z: foam speed (m/s), w: depth of the deep colour (uv)
    shape: vec4<f32>,
    // x: 1 to colour the body through the colour map, 0 for the body colours; y: 1 to colour
    // each liquid its own (a: field × the liquid's rank in rest density)
    options: vec4<f32>,
    shallows: array<vec4<f32>, 8>,
    deeps: array<vec4<f32>, 8>,
}

@group(#{MATERIAL_BIND_GROUP}) @binding(0) var<uniform> liquid: Liquid;
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var field: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(2) var field_sampler: sampler;
@group(#{MATERIAL_BIND_GROUP}) @binding(3) var color_map: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(4) var color_map_sampler: sampler;

// Taps up the screen for the depth of liquid above a pixel.
const DEPTH_TAPS: i32 = 6;

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    // The field covers the camera's whole view; the quad only the particles' bounds.
    let field_uv = (in.position.xy - view.viewport.xy) / view.viewport.zw;
    let f = textureSample(field, field_sampler, field_uv);
    let threshold = liquid.shape.x;
    // Signed distance to the surface in screen pixels: the field's excess over the threshold
    // over its screen-space gradient.
    let gradient = max(length(vec2(dpdx(f.r), dpdy(f.r))), 1e-4);
    let distance = (f.r - threshold) / gradient;
    let coverage = clamp(distance + 0.5, 0.0, 1.0);
    // The liquids' rank, averaged by the field, and its screen gradient (taken before any
    // branch): the surface between two liquids is where it crosses the half between ranks.
    let rank = f.a / max(f.r, 1e-4);
    let rank_gradient = max(length(vec2(dpdx(rank), dpdy(rank))), 1e-4);
    if coverage <= 0.0 {
        return vec4(0.0);
    }

    // Depth: how much of the column above, up to the deep colour's depth, is liquid. Each tap
    // counts with the field's own smooth rise across the surface (not a hard inside/outside),
    // and the taps lie closer than that rise is wide, so the colour has neither bands nor
    // edges where the surface above steps.
    let step_uv = liquid.shape.w / f32(DEPTH_TAPS);
    let soft = vec2(0.0, 1.0);
    var depth = 0.0;
    for (var k = 1; k <= DEPTH_TAPS; k++) {
        let uv = field_uv - vec2(0.0, step_uv * (f32(k) - 0.5));
        depth += smoothstep(soft.x, soft.y, textureSampleLevel(field, field_sampler, uv, 0.0).r);
    }
    depth /= f32(DEPTH_TAPS);
    depth = smoothstep(0.0, 1.0, depth);

    let weight = max(f.r, 1e-4);
    var body = mix(liquid.shallow.rgb, liquid.deep.rgb, depth);
    if liquid.options.y > 0.5 {
        let low = clamp(floor(rank), 0.0, 6.0);
        let side = clamp((rank - low - 0.5) / rank_gradient + 0.5, 0.0, 1.0);
        let i = u32(low);
        let below = mix(liquid.shallows[i].rgb, liquid.deeps[i].rgb, depth);
        let above = mix(liquid.shallows[i + 1u].rgb, liquid.deeps[i + 1u].rgb, depth);
        body = mix(below, above, side);
    }
    if liquid.options.x > 0.5 {
        let t = clamp(f.b / weight, 0.0, 1.0);
        let mapped = textureSampleLevel(color_map, color_map_sampler, vec2(t, 0.5), 0.0).rgb;
        body = mapped * mix(1.0, 0.7, depth);
    }
    let rim = 1.0 - smoothstep(0.0, liquid.shape.y, distance);
    var color = mix(body, liquid.rim.rgb, rim * liquid.rim.a);
    let foam = smoothstep(0.3 * liquid.shape.z, liquid.shape.z, f.g / weight);
    color = mix(color, liquid.foam.rgb, foam * liquid.foam.a);

    var out = vec4(color, coverage * mix(liquid.shallow.a, liquid.deep.a, depth));
#ifdef SRGB_OUTPUT
    out = vec4(linear_to_srgb(out.rgb), out.a);
#endif
    return out;
}
