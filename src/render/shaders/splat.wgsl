// One particle's share of the liquid field: a smooth bump (1 - r²)³ over the quad, times the
// particle's vertex colour (its field weight, weight × speed, weight × colour-map position). The
// field camera adds the splats of all particles (additive blending into a float target).

#import bevy_sprite::mesh2d_vertex_output::VertexOutput

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let d = in.uv * 2.0 - 1.0;
    let s = 1.0 - dot(d, d);
    if s <= 0.0 {
        discard;
    }
    return in.color * (s * s * s);
}
