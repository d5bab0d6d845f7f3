// Lit meshes: bones, muscles and the body surface. Two-sided Blinn-Phong with a headlight
// and a fill light, colours per vertex (linear), alpha per layer.

struct Uniforms {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;

struct VsIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

@vertex
fn vs_main(v: VsIn) -> VsOut {
    var o: VsOut;
    o.clip = u.view_proj * vec4<f32>(v.pos, 1.0);
    o.world = v.pos;
    o.normal = v.normal;
    o.color = v.color;
    return o;
}

@fragment
fn fs_main(i: VsOut) -> @location(0) vec4<f32> {
    let view = normalize(u.eye.xyz - i.world);
    var n = normalize(i.normal);
    if (dot(n, view) < 0.0) {
        n = -n;
    }
    let key = view;
    let fill = normalize(vec3<f32>(0.3, -0.4, 0.85));
    let diffuse = max(dot(n, key), 0.0) * 0.75 + max(dot(n, fill), 0.0) * 0.25;
    let h = normalize(key + view);
    let spec = pow(max(dot(n, h), 0.0), 48.0) * 0.18;
    let rgb = i.color.rgb * (0.28 + diffuse) + vec3<f32>(spec);
    return vec4<f32>(rgb, i.color.a);
}

// Screen-space overlay (legend): positions already in NDC, unlit.
@vertex
fn vs_overlay(v: VsIn) -> VsOut {
    var o: VsOut;
    o.clip = vec4<f32>(v.pos.xy, 0.0, 1.0);
    o.world = v.pos;
    o.normal = v.normal;
    o.color = v.color;
    return o;
}

@fragment
fn fs_overlay(i: VsOut) -> @location(0) vec4<f32> {
    return i.color;
}
