// Light arriving at a world point, as a fraction of the incident sunlight.
// LIGHTMAP 0: no light map, every point sees the full sun (the foundation's model).

#ifndef LIGHTMAP
#define LIGHTMAP 0
#endif

#if LIGHTMAP == 0
float lightmap_light(vec3 p)
{
    return 1.0;
}

float ground_light(vec3 p)
{
    return 1.0;
}
#endif
