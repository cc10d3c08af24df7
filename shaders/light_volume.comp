// The diffuse light volume on the GPU (src/light/volume_gpu.c): the passes of
// light_volume_build() in src/light/volume.c, in float32.  The contract is the converged
// solution of the discrete diffusion system, not the iteration; the CPU solves it in double
// by conjugate gradients preconditioned with block Jacobi on bricks plus a coarse correction
// (volume.c, precondition), these passes by the same method in floats, every scalar of the
// iteration kept on the GPU.  Bricks are LIGHT_VOLUME_BRICK cells a side; the per-brick
// passes run one invocation a brick, which walks its cells in order, so a brick's sums need
// no barrier.
//   PASS 1 (terms): per cell the source Q0 (the beam through its faces, in less out), its first
//     moment Q1, the transport extinction and the source's offset from the cell centre, from
//     3^3 samples of the extinction and of the dense light map inside the cell and 3^2 on each
//     face (both read with texelFetch and the CPU's trilinear weights).
//   PASS 2 (assemble): per cell the diagonal, the conductances to the +x, +y, +z neighbours and
//     the right-hand side; x = 0, r = b, p = 0.
//   PASS 3 (spmv, per brick): beta from PASS 4; p = z + P e + beta p into the other p
//     buffer and q = A p, the neighbours' p made on the fly from the same terms; the brick's
//     sum of p.q.
//   PASS 4 (coarse, one invocation): the coarse system's symmetric red-black Gauss-Seidel on
//     the bricks' sums of r (e, one value a brick), then the iteration's scalars: r.z (the
//     bricks' r.z plus their sums of r times e), beta, the residual, whether it converged.
//   PASS 5 (update, per brick): alpha = r.z / p.q (the bricks' sums of PASS 3); x += alpha p,
//     r -= alpha q; z = the brick's own system solved by red-black Gauss-Seidel; the brick's
//     r.z, r.r and sum of r.  START: x and r stay, and first the coarse system, A summed over
//     each brick.
//   PASS 6 (field): phi = x and the net flux per cell, the mean of its two face fluxes per
//     axis, into the RGBA32F field image.

#include "bindings.h"

#ifndef PASS
#define PASS 1
#endif

#if PASS == 3 || PASS == 5
#define GROUP 8
#elif PASS == 4
#define GROUP 1
#else
#define GROUP 256
#endif
layout(local_size_x = GROUP) in;

#ifndef LIGHT_VOLUME_BRICK
#error "light_volume.comp needs LIGHT_VOLUME_BRICK and LIGHT_VOLUME_BRICK_SWEEPS"
#endif
#define BRICK LIGHT_VOLUME_BRICK
// volume.c: the least coarse diagonal, relative to the sum of its brick's diagonals.
#define COARSE_DIAG_MIN 1e-6

uniform ivec3 cells_n;   // cells along x, y, z
uniform vec3 cell_size;  // metres
uniform vec3 box_origin; // the volume box's minimum corner, metres

// Per cell: [q0, q1.x, q1.y, q1.z] and [sigma_tr, dq.x, dq.y, dq.z].
layout(std430, binding = BIND_VOLUME_BUF_TERMS) buffer volume_terms {
    vec4 terms[];
};
// Per cell: [diag, off_x, off_y, off_z] (off: -G / dx to the +axis neighbour).
layout(std430, binding = BIND_VOLUME_BUF_SYSTEM) buffer volume_system {
    vec4 sys[];
};
// Seven vectors of cells_count floats: b, x, r, z (the bricks' part), p (two: the last
// iteration's and this one's), q.
layout(std430, binding = BIND_VOLUME_BUF_VECTORS) buffer volume_vectors {
    float cg[];
};
// The head: [0] rz, [1] bb, [2] pq, [3] alpha, [4] beta, [5] rr, [6] relative residual,
// [7] 1 once converged, [8] iterations done; then per brick four sums (p.q, r.z, r.r, sum of
// r), the coarse system (four per brick: diagonal, coupling to the +x, +y, +z brick) and e
// (one per brick).
layout(std430, binding = BIND_VOLUME_BUF_SCALARS) buffer volume_scalars {
    float scal[];
};

// light_volume.h's resistance of a surface facing clear air (the Milne-type condition), set by
// volume_gpu.c from the header so that the two builds solve one system.
#ifndef LIGHT_VOLUME_BOUNDARY_R
#error "light_volume.comp needs LIGHT_VOLUME_BOUNDARY_R"
#endif
#define BOUNDARY_R float(LIGHT_VOLUME_BOUNDARY_R)
// volume.c: the least half-cell resistance in cloud and in clear air.
#define HALF_CELL_R_MIN 0.01
#define HALF_CELL_R_AIR 0.25
#define CLEAR_SIGMA 1e-6

int cells_count()
{
    return cells_n.x * cells_n.y * cells_n.z;
}

#define B(c) cg[(c)]
#define X(c) cg[cells_count() + (c)]
#define R(c) cg[2 * cells_count() + (c)]
#define Z(c) cg[3 * cells_count() + (c)]
#define PB(k, c) cg[(4 + (k)) * cells_count() + (c)]
#define Q(c) cg[6 * cells_count() + (c)]

#define HEAD 16
ivec3 bricks_n()
{
    return (cells_n + BRICK - 1) / BRICK;
}

int bricks_count()
{
    ivec3 n = bricks_n();
    return n.x * n.y * n.z;
}

int brick_of(ivec3 idx)
{
    ivec3 b = idx / BRICK, n = bricks_n();
    return b.x + n.x * (b.y + n.y * b.z);
}

#define SUMS(b, k) scal[HEAD + 4 * (b) + (k)]
#define COARSE(b, k) scal[HEAD + 4 * bricks_count() + 4 * (b) + (k)]
#define E(b) scal[HEAD + 8 * bricks_count() + (b)]

ivec3 cell_of(int c)
{
    return ivec3(c % cells_n.x, (c / cells_n.x) % cells_n.y, c / (cells_n.x * cells_n.y));
}

int cell_index(ivec3 idx)
{
    return idx.x + cells_n.x * (idx.y + cells_n.y * idx.z);
}

int stride_of(int a)
{
    return a == 0 ? 1 : a == 1 ? cells_n.x : cells_n.x * cells_n.y;
}

float half_r(float sigma, float dx)
{
    return max(1.5 * sigma * dx, sigma < CLEAR_SIGMA ? HALF_CELL_R_AIR : HALF_CELL_R_MIN);
}

// volume.c, clearness: 1 in clear air, 0 in opaque cloud, from the cell's own optical depth.
float clearness(float sigma, float dx)
{
    return 1.0 / (1.0 + 1.5 * sigma * dx);
}

// What cell C adds to the push of the flux along +A through its face on SIDE (volume.c,
// face_push).
float face_push(int c, int a, int side, float r, float dx)
{
    vec4 t0 = terms[2 * c], t1 = terms[2 * c + 1];
    float dq = t1[1 + a];
    float shift = side == 1 ? max(dq, 0.0) : min(dq, 0.0);
    return 1.5 * dx * t0[1 + a] + 2.0 * r * shift;
}

#if PASS == 1
layout(binding = BIND_VOLUME_TEX_BETA) uniform sampler3D beta_tex;   // texelFetch only
layout(binding = BIND_VOLUME_TEX_LIGHT) uniform sampler3D light_tex; // texelFetch only
uniform ivec3 vol_n;
uniform vec3 vol_origin;
uniform vec3 vol_inv_spacing;
uniform mat4 light_world_to_tex;
uniform ivec3 light_n;
uniform vec3 sdir;      // the direction the light travels
uniform vec2 tr;        // 1 - g: water, ice
uniform vec2 loss;      // the share of the extinction that leaves the beam: water, ice
uniform vec2 gs;        // the mean cosine of what leaves it: water, ice
uniform int sub;        // samples per cell and axis
#if STRETCHED
layout(binding = BIND_VOLUME_TEX_ZMAP) uniform sampler1D zmap_tex; // texelFetch only
#endif
#include "zmap.glsl"

int axis_weight(float x, int n, out float t)
{
    float f = x - 0.5;
    if (n < 2 || f <= 0.0) {
        t = 0.0;
        return 0;
    }
    if (f >= float(n - 1)) {
        t = 1.0;
        return n - 2;
    }
    int i = int(f);
    t = f - float(i);
    return i;
}

// light_sample_beta: ice, water.
vec2 sample_beta(vec3 p)
{
    vec3 x = (p - vol_origin) * vol_inv_spacing;
    for (int a = 0; a < 3; a++) {
        if (!(x[a] >= 0.0 && x[a] <= float(vol_n[a])))
            return vec2(0.0);
    }
    x.z = zmap_voxel(p.z, vol_origin.z, float(vol_n.z), x.z); // the model's levels
    vec3 t;
    ivec3 i0, d;
    for (int a = 0; a < 3; a++) {
        float ta;
        i0[a] = axis_weight(x[a], vol_n[a], ta);
        t[a] = ta;
        d[a] = vol_n[a] > 1 ? 1 : 0;
    }
    vec2 c000 = texelFetch(beta_tex, i0, 0).rg;
    vec2 c100 = texelFetch(beta_tex, i0 + ivec3(d.x, 0, 0), 0).rg;
    vec2 c010 = texelFetch(beta_tex, i0 + ivec3(0, d.y, 0), 0).rg;
    vec2 c110 = texelFetch(beta_tex, i0 + ivec3(d.x, d.y, 0), 0).rg;
    vec2 c001 = texelFetch(beta_tex, i0 + ivec3(0, 0, d.z), 0).rg;
    vec2 c101 = texelFetch(beta_tex, i0 + ivec3(d.x, 0, d.z), 0).rg;
    vec2 c011 = texelFetch(beta_tex, i0 + ivec3(0, d.y, d.z), 0).rg;
    vec2 c111 = texelFetch(beta_tex, i0 + d, 0).rg;
    vec2 c00 = c000 + t.x * (c100 - c000);
    vec2 c10 = c010 + t.x * (c110 - c010);
    vec2 c01 = c001 + t.x * (c101 - c001);
    vec2 c11 = c011 + t.x * (c111 - c011);
    vec2 c0 = c00 + t.y * (c10 - c00);
    vec2 c1 = c01 + t.y * (c11 - c01);
    vec2 v = c0 + t.z * (c1 - c0);
    return vec2(v.x >= 0.0 ? min(v.x, 1e30) : 0.0, v.y >= 0.0 ? min(v.y, 1e30) : 0.0);
}

int tex_node(float tex, int n, out float t)
{
    float x = tex * float(n) - 0.5;
    if (!(x > 0.0)) {
        t = 0.0;
        return 0;
    }
    if (x >= float(n - 1)) {
        t = 1.0;
        return n - 2;
    }
    int i = int(x);
    t = x - float(i);
    return i;
}

// The beam at P (light_map_sample; 1 beside the light columns).
float beam_at(vec3 p)
{
    vec3 tex = (light_world_to_tex * vec4(p, 1.0)).xyz;
    if (!(tex.x >= 0.0 && tex.x <= 1.0 && tex.y >= 0.0 && tex.y <= 1.0))
        return 1.0;
    ivec3 i;
    vec3 t;
    for (int a = 0; a < 3; a++) {
        float ta;
        i[a] = tex_node(tex[a], light_n[a], ta);
        t[a] = ta;
    }
    float c[4];
    for (int dk = 0; dk < 2; dk++) {
        for (int dj = 0; dj < 2; dj++) {
            float a0 = texelFetch(light_tex, ivec3(i.x, i.y + dj, i.z + dk), 0).r;
            float a1 = texelFetch(light_tex, ivec3(i.x + 1, i.y + dj, i.z + dk), 0).r;
            c[2 * dk + dj] = a0 + t.x * (a1 - a0);
        }
    }
    float c0 = c[0] + t.y * (c[1] - c[0]);
    float c1 = c[2] + t.y * (c[3] - c[2]);
    return c0 + t.z * (c1 - c0);
}

// The beam over face F of the cells (volume.c, face_beam): its mean and its first moments
// about the face's centre along axes (A + 1) % 3 and (A + 2) % 3.  1 on a face of the box toward
// the sun.  The points depend on F alone: both cells of a face see the same beam through it.
vec3 face_beam(int a, ivec3 f)
{
    int b = (a + 1) % 3, c = (a + 2) % 3;
    if ((f[a] == 0 && sdir[a] > 0.0) || (f[a] == cells_n[a] && sdir[a] < 0.0))
        return vec3(1.0, 0.0, 0.0);
    vec3 m = vec3(0.0);
    for (int y = 0; y < sub; y++) {
        for (int x = 0; x < sub; x++) {
            float ob = ((float(x) + 0.5) / float(sub) - 0.5) * cell_size[b];
            float oc = ((float(y) + 0.5) / float(sub) - 0.5) * cell_size[c];
            vec3 p;
            p[a] = box_origin[a] + float(f[a]) * cell_size[a];
            p[b] = box_origin[b] + (float(f[b]) + 0.5) * cell_size[b] + ob;
            p[c] = box_origin[c] + (float(f[c]) + 0.5) * cell_size[c] + oc;
            float l = beam_at(p);
            m += l * vec3(1.0, ob, oc);
        }
    }
    return m / float(sub * sub);
}

// volume.c, cell_terms: the source from the beam through the cell's faces, only where the
// cell holds cloud; the centroid from the same faces and the beam inside the cell.
void main()
{
    int c = int(gl_GlobalInvocationID.x);
    if (c >= cells_count())
        return;
    ivec3 ijk = cell_of(c);
    float m = float(sub * sub * sub);
    float sigma = 0.0, wg = 0.0, wsum = 0.0;
    for (int k = 0; k < sub; k++) {
        for (int j = 0; j < sub; j++) {
            for (int i = 0; i < sub; i++) {
                vec3 p = box_origin + (vec3(ijk) + (vec3(i, j, k) + 0.5) / float(sub)) * cell_size;
                vec2 b = sample_beta(p);
                float ice = b.x, water = b.y;
                sigma += tr.y * ice + tr.x * water;
                float lw = loss.x * water, li = loss.y * ice;
                wg += lw * gs.x + li * gs.y;
                wsum += lw + li;
            }
        }
    }
    if (!(wsum > 0.0)) {
        terms[2 * c] = vec4(0.0);
        terms[2 * c + 1] = vec4(sigma / m, 0.0, 0.0, 0.0);
        return;
    }
    float q0 = 0.0;
    vec3 dq = vec3(0.0);
    for (int a = 0; a < 3; a++) {
        if (sdir[a] == 0.0)
            continue;
        int b = (a + 1) % 3, cc = (a + 2) % 3;
        for (int side = 0; side < 2; side++) {
            ivec3 f = ijk;
            f[a] += side;
            vec3 fb = face_beam(a, f);
            float in_s = side == 1 ? -sdir[a] : sdir[a];
            q0 += in_s * fb.x / cell_size[a];
            dq[a] += in_s * fb.x * (side == 1 ? 0.5 : -0.5);
            dq[b] += in_s * fb.y / cell_size[a];
            dq[cc] += in_s * fb.z / cell_size[a];
        }
    }
    float inside = 0.0;
    for (int k = 0; k < sub; k++) {
        for (int j = 0; j < sub; j++) {
            for (int i = 0; i < sub; i++)
                inside += beam_at(box_origin +
                                  (vec3(ijk) + (vec3(i, j, k) + 0.5) / float(sub)) * cell_size);
        }
    }
    inside /= m;
    q0 = max(q0, 0.0);
    vec3 lim = 0.5 * cell_size * q0;
    dq = clamp(dq + sdir * inside, -lim, lim);
    terms[2 * c] = vec4(q0, q0 * (wg / wsum) * sdir);
    terms[2 * c + 1] = vec4(sigma / m, dq);
}

#elif PASS == 2
void main()
{
    int c = int(gl_GlobalInvocationID.x);
    if (c >= cells_count())
        return;
    ivec3 idx = cell_of(c);
    vec4 t0 = terms[2 * c], t1 = terms[2 * c + 1];
    float diag = 0.0, rhs = t0.x;
    vec3 off = vec3(0.0);
    for (int a = 0; a < 3; a++) {
        float dx = cell_size[a];
        float ra = half_r(t1.x, dx), ca = clearness(t1.x, dx);
        for (int side = 0; side < 2; side++) {
            bool edge = side == 0 ? idx[a] == 0 : idx[a] == cells_n[a] - 1;
            if (edge) {
                float g = 1.0 / (ra + BOUNDARY_R) / dx;
                float push = face_push(c, a, side, ra, dx) * (side == 1 ? 1.0 : -1.0);
                diag += g;
                rhs -= g * push;
                continue;
            }
            int o = side == 0 ? c - stride_of(a) : c + stride_of(a);
            float rb = half_r(terms[2 * o + 1].x, dx), cb = clearness(terms[2 * o + 1].x, dx);
            float g = 1.0 / (ra + rb + BOUNDARY_R * abs(ca - cb)) / dx;
            diag += g;
            // the flux along +a through this face, lower cell first
            int lo = side == 0 ? o : c, hi = side == 0 ? c : o;
            float rl = side == 0 ? rb : ra, rh = side == 0 ? ra : rb;
            float b = face_push(lo, a, 1, rl, dx) + face_push(hi, a, 0, rh, dx);
            rhs += side == 0 ? g * b : -g * b;
            if (side == 1)
                off[a] = -g;
        }
    }
    sys[c] = vec4(diag, off);
    B(c) = rhs;
    X(c) = 0.0;
    R(c) = rhs;
    PB(0, c) = 0.0;
    PB(1, c) = 0.0;
}

#elif PASS == 3 || PASS == 5
uniform int parity; // this iteration's p buffer

// The cells of brick B: [lo, hi).
int brick_cells(out ivec3 lo, out ivec3 hi)
{
    int b = int(gl_GlobalInvocationID.x);
    ivec3 n = bricks_n();
    ivec3 bi = ivec3(b % n.x, (b / n.x) % n.y, b / (n.x * n.y));
    lo = bi * BRICK;
    hi = min(lo + BRICK, cells_n);
    return b;
}

#if PASS == 3
// This iteration's direction at cell IDX: z + P e + beta p.
float direction(ivec3 idx, float beta)
{
    int c = cell_index(idx);
    return Z(c) + E(brick_of(idx)) + beta * PB(1 - parity, c);
}

void main()
{
    int b = int(gl_GlobalInvocationID.x);
    if (b >= bricks_count() || scal[7] != 0.0)
        return;
    ivec3 lo, hi;
    brick_cells(lo, hi);
    float beta = scal[4], pq = 0.0;
    for (int k = lo.z; k < hi.z; k++) {
        for (int j = lo.y; j < hi.y; j++) {
            for (int i = lo.x; i < hi.x; i++) {
                ivec3 idx = ivec3(i, j, k);
                int c = cell_index(idx);
                vec4 s = sys[c];
                float pc = direction(idx, beta);
                float v = s.x * pc;
                for (int a = 0; a < 3; a++) {
                    ivec3 e = ivec3(0);
                    e[a] = 1;
                    if (idx[a] + 1 < cells_n[a])
                        v += s[1 + a] * direction(idx + e, beta);
                    if (idx[a] > 0)
                        v += sys[c - stride_of(a)][1 + a] * direction(idx - e, beta);
                }
                PB(parity, c) = pc;
                Q(c) = v;
                pq += pc * v;
            }
        }
    }
    SUMS(b, 0) = pq;
}

#else
uniform int start; // 1: the start, r = b; the coarse system first

// One half sweep of red-black Gauss-Seidel on the brick's own system over the cells of
// COLOUR (the parity of i + j + k).
void half_sweep(ivec3 lo, ivec3 hi, int colour)
{
    for (int k = lo.z; k < hi.z; k++) {
        for (int j = lo.y; j < hi.y; j++) {
            for (int i = lo.x + ((lo.x + j + k + colour) & 1); i < hi.x; i += 2) {
                ivec3 idx = ivec3(i, j, k);
                int c = cell_index(idx);
                vec4 s = sys[c];
                float v = R(c);
                for (int a = 0; a < 3; a++) {
                    int st = stride_of(a);
                    if (idx[a] + 1 < hi[a])
                        v -= s[1 + a] * Z(c + st);
                    if (idx[a] > lo[a])
                        v -= sys[c - st][1 + a] * Z(c - st);
                }
                Z(c) = v / s.x;
            }
        }
    }
}

void main()
{
    int b = int(gl_GlobalInvocationID.x);
    if (b >= bricks_count() || scal[7] != 0.0)
        return;
    ivec3 lo, hi;
    brick_cells(lo, hi);
    if (start == 1) {
        // P^T A P, P constant over each brick: the faces inside a brick cancel.
        vec4 cs = vec4(0.0);
        float diags = 0.0;
        for (int k = lo.z; k < hi.z; k++) {
            for (int j = lo.y; j < hi.y; j++) {
                for (int i = lo.x; i < hi.x; i++) {
                    ivec3 idx = ivec3(i, j, k);
                    vec4 s = sys[cell_index(idx)];
                    cs.x += s.x;
                    diags += s.x;
                    for (int a = 0; a < 3; a++) {
                        if (idx[a] + 1 >= cells_n[a])
                            continue;
                        if (idx[a] + 1 < hi[a])
                            cs.x += 2.0 * s[1 + a];
                        else
                            cs[1 + a] += s[1 + a];
                    }
                }
            }
        }
        // What the cancellation leaves may be below the floats' rounding (a clear brick
        // walled in by opaque cloud): the diagonal alone then, still positive definite.
        if (!(cs.x > COARSE_DIAG_MIN * diags))
            cs.x = diags;
        for (int k = 0; k < 4; k++)
            COARSE(b, k) = cs[k];
    } else {
        float pq = 0.0;
        for (int g = 0; g < bricks_count(); g++)
            pq += SUMS(g, 0);
        float alpha = pq > 0.0 ? scal[0] / pq : 0.0;
        if (b == 0) {
            scal[2] = pq;
            scal[3] = alpha;
        }
        for (int k = lo.z; k < hi.z; k++) {
            for (int j = lo.y; j < hi.y; j++) {
                for (int i = lo.x; i < hi.x; i++) {
                    int c = cell_index(ivec3(i, j, k));
                    X(c) += alpha * PB(parity, c);
                    R(c) -= alpha * Q(c);
                }
            }
        }
    }
    for (int k = lo.z; k < hi.z; k++) {
        for (int j = lo.y; j < hi.y; j++) {
            for (int i = lo.x; i < hi.x; i++)
                Z(cell_index(ivec3(i, j, k))) = 0.0;
        }
    }
    for (int h = 0; h <= 2 * LIGHT_VOLUME_BRICK_SWEEPS; h++)
        half_sweep(lo, hi, h & 1);
    float rz = 0.0, rr = 0.0, rs = 0.0;
    for (int k = lo.z; k < hi.z; k++) {
        for (int j = lo.y; j < hi.y; j++) {
            for (int i = lo.x; i < hi.x; i++) {
                int c = cell_index(ivec3(i, j, k));
                float r = R(c);
                rz += r * Z(c);
                rr += r * r;
                rs += r;
            }
        }
    }
    SUMS(b, 1) = rz;
    SUMS(b, 2) = rr;
    SUMS(b, 3) = rs;
}
#endif

#elif PASS == 4
uniform int start;      // 1: the start (bb, no beta)
uniform float tolerance; // the relative residual the solve stops at
void main()
{
    if (scal[7] != 0.0)
        return;
    ivec3 n = bricks_n();
    int m = bricks_count();
    for (int b = 0; b < m; b++)
        E(b) = 0.0;
    for (int h = 0; h <= 2 * LIGHT_VOLUME_COARSE_SWEEPS; h++) {
        for (int k = 0; k < n.z; k++) {
            for (int j = 0; j < n.y; j++) {
                for (int i = (j + k + h) & 1; i < n.x; i += 2) {
                    int b = i + n.x * (j + n.y * k);
                    ivec3 idx = ivec3(i, j, k);
                    ivec3 st = ivec3(1, n.x, n.x * n.y);
                    float v = SUMS(b, 3);
                    for (int a = 0; a < 3; a++) {
                        if (idx[a] + 1 < n[a])
                            v -= COARSE(b, 1 + a) * E(b + st[a]);
                        if (idx[a] > 0)
                            v -= COARSE(b - st[a], 1 + a) * E(b - st[a]);
                    }
                    E(b) = v / COARSE(b, 0);
                }
            }
        }
    }
    float rz = 0.0, rr = 0.0;
    for (int b = 0; b < m; b++) {
        rz += SUMS(b, 1) + SUMS(b, 3) * E(b);
        rr += SUMS(b, 2);
    }
    if (start == 1) {
        scal[1] = rr;
        scal[4] = 0.0;
        scal[6] = rr > 0.0 ? 1.0 : 0.0;
        scal[7] = rr > 0.0 ? 0.0 : 1.0;
        scal[8] = 0.0;
    } else {
        scal[4] = scal[0] > 0.0 ? rz / scal[0] : 0.0;
        float res = scal[1] > 0.0 ? sqrt(max(rr, 0.0) / scal[1]) : 0.0;
        scal[6] = res;
        scal[8] += 1.0;
        // a residual that is not a number stops the solve too (the CPU reports it)
        if (!(res > tolerance))
            scal[7] = 1.0;
    }
    scal[0] = rz;
    scal[5] = rr;
}

#elif PASS == 6
layout(rgba32f, binding = BIND_VOLUME_IMG_FIELD) uniform writeonly image3D field_img;
void main()
{
    int c = int(gl_GlobalInvocationID.x);
    if (c >= cells_count())
        return;
    ivec3 idx = cell_of(c);
    float phi = X(c);
    vec4 t1 = terms[2 * c + 1];
    vec3 flux;
    for (int a = 0; a < 3; a++) {
        float dx = cell_size[a];
        float ra = half_r(t1.x, dx), ca = clearness(t1.x, dx);
        float face[2];
        for (int side = 0; side < 2; side++) {
            bool edge = side == 0 ? idx[a] == 0 : idx[a] == cells_n[a] - 1;
            if (edge) {
                float nout = side == 0 ? -1.0 : 1.0;
                float fo = (phi + face_push(c, a, side, ra, dx) * nout) / (ra + BOUNDARY_R);
                face[side] = fo * nout;
                continue;
            }
            int o = side == 0 ? c - stride_of(a) : c + stride_of(a);
            float rb = half_r(terms[2 * o + 1].x, dx), cb = clearness(terms[2 * o + 1].x, dx);
            float r = ra + rb + BOUNDARY_R * abs(ca - cb);
            int lo = side == 0 ? o : c, hi = side == 0 ? c : o;
            float rl = side == 0 ? rb : ra, rh = side == 0 ? ra : rb;
            face[side] = (X(lo) - X(hi) + face_push(lo, a, 1, rl, dx) +
                          face_push(hi, a, 0, rh, dx)) / r;
        }
        flux[a] = 0.5 * (face[0] + face[1]);
    }
    imageStore(field_img, idx, vec4(phi, flux));
}
#endif
