// The liquid surface: turns the splatted field (r: particle field, 1 inside a fluid at rest;
// g: field × speed; b: field × colour-map position) into a body with an anti-aliased edge where
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
    // x: 1 to colour the body through the colour map, 0 for the body colours
    options: vec4<f32>,
}

@group(#{MATERIAL_BIND_GROUP}) @binding(0) var<uniform> liquid: Liquid;
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var field: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(2) var field_sampler: sampler;
@group(#{MATERIAL_BIND_GROUP}) @binding(3) var color_map: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(4) var color_map_sampler: sampler;

// Taps up the screen for the depth of liquid above a pixel, and halvings of the tap that
// brackets the surface.
const DEPTH_TAPS: i32 = 4;
const REFINE_STEPS: i32 = 3;

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
    if coverage <= 0.0 {
        return vec4(0.0);
    }

    // Depth below the surface straight above, as a fraction of the deep colour's depth: the
    // first of the taps up the screen that is outside the liquid brackets the surface, and a
    // few halvings of the bracket place it to a pixel or two (continuous: no colour bands).
    let step_uv = liquid.shape.w / f32(DEPTH_TAPS);
    var inside = 0.0;
    var outside = -1.0;
    for (var k = 1; k <= DEPTH_TAPS; k++) {
        let uv = field_uv - vec2(0.0, step_uv * f32(k));
        let here = textureSampleLevel(field, field_sampler, uv, 0.0).r;
        if outside < 0.0 {
            if here < threshold {
                outside = f32(k);
            } else {
                inside = f32(k);
            }
        }
    }
    var depth = 1.0;
    if outside > 0.0 {
        for (var k = 0; k < REFINE_STEPS; k++) {
            let middle = 0.5 * (inside + outside);
            let uv = field_uv - vec2(0.0, step_uv * middle);
            if textureSampleLevel(field, field_sampler, uv, 0.0).r < threshold {
                outside = middle;
            } else {
                inside = middle;
            }
        }
        depth = 0.5 * (inside + outside) / f32(DEPTH_TAPS);
    }
    depth = smoothstep(0.0, 1.0, depth);

    let weight = max(f.r, 1e-4);
    var body = mix(liquid.shallow.rgb, liquid.deep.rgb, depth);
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
