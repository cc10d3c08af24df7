// The volume's height mapping (data/volume.h): world height -> continuous voxel coordinate
// along z.  STRETCHED 0: a uniform grid, (z - box bottom) / spacing.  STRETCHED 1: the
// model's own levels, read from the table grid3_zmap_fill makes (ZMAP_N values of the
// voxel coordinate over n_z at evenly spaced heights of the box, r, and the level thickness
// there, g; then the n_z level centres' heights, r), linear between its entries with the same float operations as the CPU light map
// build (src/light/transport.c, sampler_z).  The including program binds the table at
// ZMAP_BINDING and sets zmap_n and zmap_inv_height (1 / the box's height, 1/m).

#ifndef STRETCHED
#define STRETCHED 0
#endif

#if STRETCHED
layout(binding = ZMAP_BINDING) uniform sampler1D zmap_tex; // texelFetch only
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

#if STRETCHED
// Along a ray from height Z rising DZ_DIR per unit length (the ray's dir.z), the distance to
// where it next crosses a level centre's height, at least MIN ahead; 1e30: none ahead.  Steps
// cut there see the extinction linear in height over each (a level's value is at its centre).
float zmap_next_centre(float z, float dz_dir, float bottom, float n_z, float min_dist)
{
    if (abs(dz_dir) < 1e-6)
        return 1e30;
    float u = zmap_voxel(z, bottom, n_z, 0.0) - 0.5; // centre k at u = k
    int n = int(n_z + 0.5);
    int k = dz_dir > 0.0 ? int(floor(u)) + 1 : int(ceil(u)) - 1;
    for (int it = 0; it < 2; it++) {
        if (k < 0 || k >= n)
            return 1e30;
        float d = (texelFetch(zmap_tex, zmap_n + k, 0).r - z) / dz_dir;
        if (d >= min_dist)
            return d;
        k += dz_dir > 0.0 ? 1 : -1; // rounding put the crossing behind: the next one
    }
    return 1e30;
}
#endif
