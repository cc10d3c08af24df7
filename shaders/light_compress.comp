// Deep light map, compressed on the GPU (Nes §5.3.4, Algorithm 2; Lokovic-Veach): every light
// column of the dense map replaced by nodes between which linear interpolation stays within
// epsilon of every node plane's value.  One invocation per column runs compress_channels() of
// src/light/compress.c operation for operation (in double, as it does): CHANNELS 1 the light
// (light_compress_column), CHANNELS 2 the diffuse light's M and N together
// (light_compress_column2).  PASS 1 counts each column's nodes into columns[base + 2 c + 1];
// light_scan.comp turns the counts into first indices columns[base + 2 c]; PASS 2 runs the
// same compression again and writes the nodes there, from nodes[node_base] on (depth and the
// CHANNELS values).  Columns c = i + n0 j.

#include "bindings.h"

#ifndef PASS
#define PASS 1
#endif
#ifndef CHANNELS
#define CHANNELS 1
#endif

layout(local_size_x = 8, local_size_y = 8) in;

#if CHANNELS == 1
layout(r32f, binding = BIND_COMPRESS_IMG_VALUES) uniform readonly image3D values_img;
// (the values: one or two per node)
#else
layout(rg32f, binding = BIND_COMPRESS_IMG_VALUES) uniform readonly image3D values_img;

#endif
layout(std430, binding = BIND_COMPRESS_BUF_COLUMNS) buffer light_columns {
    uint columns[];
};
#if PASS == 2
layout(std430, binding = BIND_COMPRESS_BUF_NODES) writeonly buffer light_nodes {
    float nodes[];
};
#endif

uniform ivec3 grid_n;
uniform int base_y;     // the first row of columns of this dispatch (a build in pieces)
uniform double epsilon;
uniform uint base;      // this part's first word in columns[]
uniform uint node_base; // and in nodes[]

uint first_node;

#if CHANNELS == 1
#define DVEC double
double load(ivec2 ij, int k)
{
    return double(imageLoad(values_img, ivec3(ij, k)).r);
}
bool all_le(double a, double b)
{
    return a <= b;
}
// Whether every value's slope range holds 0: flat within epsilon.
bool level_run(double lo, double hi)
{
    return lo <= 0.0lf && hi >= 0.0lf;
}
#else
#define DVEC dvec2
dvec2 load(ivec2 ij, int k)
{
    return dvec2(imageLoad(values_img, ivec3(ij, k)).rg);
}
bool all_le(dvec2 a, dvec2 b)
{
    return a.x <= b.x && a.y <= b.y;
}
bool level_run(dvec2 lo, dvec2 hi)
{
    return lo.x <= 0.0lf && hi.x >= 0.0lf && lo.y <= 0.0lf && hi.y >= 0.0lf;
}
#endif

void emit(inout int m, double depth, DVEC value)
{
#if PASS == 2
    uint at = node_base + uint(CHANNELS + 1) * (first_node + uint(m));
    nodes[at] = float(depth);
#if CHANNELS == 1
    nodes[at + 1u] = float(value);
#else
    nodes[at + 1u] = float(value.x);
    nodes[at + 2u] = float(value.y);
#endif
#endif
    m++;
}

void main()
{
    ivec2 ij = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, base_y);
    if (ij.x >= grid_n.x || ij.y >= grid_n.y)
        return;
    uint col = uint(ij.x + grid_n.x * ij.y);
#if PASS == 2
    first_node = columns[base + 2u * col];
#endif
    int count = grid_n.z;
    int m = 0;
    double pd = 0.0lf;
    DVEC pv = load(ij, 0); // the current segment's start node
    emit(m, pd, pv);
    DVEC lo = DVEC(0.0lf), hi = DVEC(0.0lf); // feasible slopes from the node (members > 0)
    int members = 0;                         // samples after the node in the segment
    DVEC prev = pv;                          // the previous sample's values
    for (int c = 1; c < count; c++) {
        double dc = double(c);
        DVEC vc = load(ij, c);
        bool open = true;
        if (members > 0) {
            double dd = dc - pd;
            DVEC slo = max(lo, (vc - epsilon - pv) / dd); // Nes eq. 5.15
            DVEC shi = min(hi, (vc + epsilon - pv) / dd); // Nes eq. 5.14
            if (all_le(slo, shi)) {
                lo = slo;
                hi = shi;
                members++;
                open = false;
            } else {
                // End the segment at the previous sample on the slope every member accepts
                // nearest the sample's own (compress.c).
                double dp = double(c - 1);
                DVEC s = clamp((prev - pv) / (dp - pd), lo, hi);
                if (m == 1 && level_run(lo, hi)) {
                    s = DVEC(0.0lf); // a flat start: the next node alone stands for it
                    m = 0;
                }
                pv = pv + s * (dp - pd);
                pd = dp;
                emit(m, pd, pv);
                members = 0;
            }
        }
        if (open) {
            // Depths are the node planes' indices: never equal, so never a step.
            double dd = dc - pd;
            lo = (vc - epsilon - pv) / dd;
            hi = (vc + epsilon - pv) / dd;
            members = 1;
        }
        prev = vc;
    }
    // A flat tail needs no closing node: lookups clamp to the last node's value after it.
    if (members > 0 && !level_run(lo, hi)) {
        double dl = double(count - 1);
        DVEC s = clamp((prev - pv) / (dl - pd), lo, hi);
        emit(m, dl, pv + s * (dl - pd));
    }
#if PASS == 1
    columns[base + 2u * col + 1u] = uint(m);
#endif
}
