// Shared helpers of the eye and light passes.  World frame: metres, x east, y north, z up.

const float PI = 3.14159265358979;

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
