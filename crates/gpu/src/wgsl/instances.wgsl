// Instancing, mirroring crates/bvh/src/instance.rs (`TwoLevel`: a box BVH over the
// placements, one tree per object) and the instanced branch of
// crates/tracer/src/integrator.rs (`SceneView::surface_at`, `triangle_source`). Each
// placed object's triangles and tree are uploaded once; a placement is a record in the
// tables (`backend::INSTANCE_FLOATS`): world-to-object and object-to-world as rows of a
// 3×4 matrix, the normal matrix's rows with the orientation, the object tree's root, the
// replacing material and the CPU's id of its first triangle.

// The 3×4 affine matrix at `at` (rows of four floats) applied to the point p.
fn pt_affine_point(at: u32, p: vec3f) -> vec3f {
    let r0 = vec4f(pt_tv3(at), pt_tables[at + 3u]);
    let r1 = vec4f(pt_tv3(at + 4u), pt_tables[at + 7u]);
    let r2 = vec4f(pt_tv3(at + 8u), pt_tables[at + 11u]);
    let q = vec4f(p, 1.0);
    return vec3f(dot(r0, q), dot(r1, q), dot(r2, q));
}

// The linear part of the 3×4 matrix (rows of four floats) at `at`, applied to v.
fn pt_affine_vector(at: u32, v: vec3f) -> vec3f {
    return vec3f(dot(pt_tv3(at), v), dot(pt_tv3(at + 4u), v), dot(pt_tv3(at + 8u), v));
}

// `TwoLevel`'s leaf: the ray taken into the object's space (the direction not
// renormalised, so t stays the world's) and traced through the object's tree.
fn pt_trace_instance(rec: u32, r: PtRay, t_max: f32, any_hit: bool) -> PtHit {
    let local = pt_make_ray(pt_affine_point(rec, r.o), pt_affine_vector(rec, r.d), r.t_min);
    var h = pt_trace_triangles(pt_tu(rec + 31u), local, t_max, any_hit);
    if h.prim != PT_NO_HIT {
        h.inst = rec;
    }
    return h;
}

// Whether a hit is on a placed object's triangle.
fn pt_is_instanced(hit: PtHit) -> bool {
    return PT_HAS_INSTANCES && hit.inst != PT_NO_HIT;
}

// A triangle hit's vertices in world space.
fn pt_hit_triangle(hit: PtHit) -> array<vec3f, 3> {
    let i = hit.prim;
    var v = array<vec3f, 3>(pt_tri_verts[3u * i].xyz, pt_tri_verts[3u * i + 1u].xyz, pt_tri_verts[3u * i + 2u].xyz);
    if pt_is_instanced(hit) {
        let to_world = hit.inst + 12u;
        v = array<vec3f, 3>(pt_affine_point(to_world, v[0]), pt_affine_point(to_world, v[1]), pt_affine_point(to_world, v[2]));
    }
    return v;
}

// The placement's orientation: −1 where it mirrors (its world winding is reversed, and
// the object's front stays front).
fn pt_instance_orientation(hit: PtHit) -> f32 {
    if pt_is_instanced(hit) {
        return pt_tables[hit.inst + 27u];
    }
    return 1.0;
}

// An object-space shading normal in world space (the normal matrix: the inverse transpose).
fn pt_instance_normal(hit: PtHit, n: vec3f) -> vec3f {
    if pt_is_instanced(hit) {
        let at = hit.inst + 24u;
        return vec3f(dot(pt_tv3(at), n), dot(pt_tv3(at + 4u), n), dot(pt_tv3(at + 8u), n));
    }
    return n;
}

// An object-space tangent in world space.
fn pt_instance_tangent(hit: PtHit, t: vec3f) -> vec3f {
    if pt_is_instanced(hit) {
        return pt_affine_vector(hit.inst + 12u, t);
    }
    return t;
}

// The material of a triangle hit whose triangle names `own`: the placement's where it
// replaces the object's.
fn pt_instance_material(hit: PtHit, own: u32) -> u32 {
    if pt_is_instanced(hit) {
        let m = pt_tu(hit.inst + 35u);
        if m != PT_NO_HIT {
            return m;
        }
    }
    return own;
}

// The CPU's primitive id of a triangle hit whose triangle stores `own` (an object's
// triangle stores its index in the object; the placement's first id is added).
fn pt_instance_cpu_prim(hit: PtHit, own: u32) -> u32 {
    if pt_is_instanced(hit) {
        return pt_tu(hit.inst + 36u) + own;
    }
    return own;
}
