// The volume's height mapping (data/volume.h): world height -> continuous voxel coordinate
// along z.  STRETCHED 0: a uniform grid, (z - box bottom) / spacing.  STRETCHED 1: the
// model's own levels, read from the table grid3_zmap_fill makes (ZMAP_N values of the
// voxel coordinate over n_z at evenly spaced heights of the box, r, and the level thickness
// there, g), linear between its entries with the same float operations as the CPU light map
// build (src/light/transport.c, sampler_z).  With STRETCHED 1 the including program declares
// `uniform sampler1D zmap_tex` at its own binding and sets zmap_n and zmap_inv_height (1 / the
// box's height, 1/m).

#ifndef STRETCHED
#define STRETCHED 0
#endif

#if STRETCHED
uniform int zmap_n;
uniform float zmap_inv_height;
#endif

// The voxel coordinate along z of height Z on a volume of N_Z levels from BOTTOM; UNIFORM_X is
// the uniform grid's (z - bottom) / spacing, returned as it is without a table.  Heights
// outside the box read the box's faces.
float zmap_voxel(float z, float bottom, float n_z, float uniform_x)
{
#if STRETCHED
    float h = clamp((z - bottom) * zmap_inv_height, 0.0, 1.0);
    float f = h * float(zmap_n - 1);
    int i = min(int(f), zmap_n - 2);
    float t = f - float(i);
    float a = texelFetch(zmap_tex, i, 0).r, b = texelFetch(zmap_tex, i + 1, 0).r;
    return (a + t * (b - a)) * n_z;
#else
    return uniform_x;
#endif
}

// The level thickness at height Z (m): the local vertical spacing; SPACING without a table.
float zmap_dz(float z, float bottom, float spacing)
{
#if STRETCHED
    float h = clamp((z - bottom) * zmap_inv_height, 0.0, 1.0);
    return texelFetch(zmap_tex, min(int(h * float(zmap_n - 1) + 0.5), zmap_n - 1), 0).g;
#else
    return spacing;
#endif
}

