// Shared helpers of the eye and light passes.  World frame: metres, x east, y north, z up.

const float PI = 3.14159265358979;

// A pixel's ray (NDC x, y): its start on the near plane and its unit direction, world metres.
// The projection and the view are inverted apart, in double on the CPU: one inverse of their
// product, unprojecting the far plane too, loses ~0.1 % of the direction in floats when far /
// near is ~1e5, and a ray that misses its own pixel's ground point stops short of or beyond
// it.  The ray runs from the near point N away from the projection's centre, inv_proj's
// column 2 (the eye, or a point at infinity for a parallel projection); no far point is used.
// The eye pass and the opaque pass both take their rays from here, so they agree.
void view_ray(mat4 inv_proj, mat4 inv_view, vec2 ndc, out vec3 origin, out vec3 dir)
{
    vec4 n = inv_proj * vec4(ndc, -1.0, 1.0);
    vec4 c = inv_proj[2];
    vec3 d = n.w * c.xyz - c.w * n.xyz;
    if (n.w < 0.0)
        d = -d;
    origin = (inv_view * vec4(n.xyz / n.w, 1.0)).xyz;
    dir = normalize(mat3(inv_view) * d);
}

// Ray / axis-aligned box intersection that stays finite when a direction component is zero:
// such a component gets a tiny signed stand-in so the slab test sees +-huge, never NaN.
vec3 dir_stand_in(vec3 dir)
{
    vec3 d = dir;
    for (int i = 0; i < 3; i++) {
        if (abs(d[i]) < 1e-20)
            d[i] = d[i] < 0.0 ? -1e-20 : 1e-20;
    }
    return d;
}

vec2 ray_box(vec3 origin, vec3 dir, vec3 box_min, vec3 box_max)
{
    vec3 inv = 1.0 / dir_stand_in(dir);
    vec3 t0 = (box_min - origin) * inv;
    vec3 t1 = (box_max - origin) * inv;
    vec3 tmin = min(t0, t1), tmax = max(t0, t1);
    return vec2(max(max(tmin.x, tmin.y), tmin.z), min(min(tmax.x, tmax.y), tmax.z));
}

// Transmittance of a sample of optical depth tau, safe for tau >> 100 (exp underflows to 0).
float transmittance(float tau)
{
    return exp(-min(tau, 80.0));
}
