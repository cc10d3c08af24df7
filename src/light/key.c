/* Rebuild on change: the key of everything a light map depends on, and a build counter. */
#include <math.h>
#include <string.h>

#include "common/log.h"
#include "light/light.h"

void light_key_init(struct light_key *k, const struct grid3 *box, const double sun[3],
                    uint64_t volume_id, uint64_t volume_generation, const struct light_settings *s)
{
    memset(k, 0, sizeof(*k));
    k->box = *box;
    double len = sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]);
    for (int a = 0; a < 3; a++)
        k->sun[a] = len > 0.0 ? sun[a] / len : sun[a];
    k->volume_id = volume_id;
    k->volume_generation = volume_generation;
    k->settings = *s;
}

/* Visits every field that matters, in a fixed order, for both equality and hashing. */
struct visit {
    uint64_t hash;
    const struct light_key *other;
    bool equal;
};

static void visit_bytes(struct visit *v, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) {
        v->hash ^= b[i];
        v->hash *= 1099511628211ull; /* FNV-1a 64 */
    }
}

static void visit_double(struct visit *v, double a, double b)
{
    if (a == 0.0)
        a = 0.0; /* -0.0 hashes as 0.0 */
    visit_bytes(v, &a, sizeof(a));
    if (v->other && !(a == b || (isnan(a) && isnan(b))))
        v->equal = false;
}

static void visit_u64(struct visit *v, uint64_t a, uint64_t b)
{
    visit_bytes(v, &a, sizeof(a));
    if (v->other && a != b)
        v->equal = false;
}

static void visit_key(struct visit *v, const struct light_key *k)
{
    const struct light_key *o = v->other ? v->other : k;
    for (int a = 0; a < 3; a++) {
        visit_u64(v, (uint64_t)(int64_t)k->box.n[a], (uint64_t)(int64_t)o->box.n[a]);
        visit_double(v, k->box.spacing[a], o->box.spacing[a]);
        visit_double(v, k->box.origin[a], o->box.origin[a]);
        visit_double(v, k->sun[a], o->sun[a]);
    }
    /* A stretched box's levels (the same box on other levels is another map). */
    visit_u64(v, (uint64_t)(int64_t)k->box.z_levels, (uint64_t)(int64_t)o->box.z_levels);
    for (int l = 0; l < k->box.z_levels && l < o->box.z_levels; l++)
        visit_double(v, k->box.z_centre[l], o->box.z_centre[l]);
    visit_u64(v, k->volume_id, o->volume_id);
    visit_u64(v, k->volume_generation, o->volume_generation);
    const struct light_settings *s = &k->settings, *t = &o->settings;
    for (int a = 0; a < 3; a++)
        visit_u64(v, (uint64_t)(int64_t)s->resolution[a], (uint64_t)(int64_t)t->resolution[a]);
    visit_double(v, s->forward_angle_deg, t->forward_angle_deg);
    visit_u64(v, s->forward, t->forward);
    visit_u64(v, s->peripheral, t->peripheral);
    visit_double(v, s->cp.water_ctr, t->cp.water_ctr);
    visit_double(v, s->cp.water_per, t->cp.water_per);
    visit_double(v, s->cp.ice_ctr, t->cp.ice_ctr);
    visit_double(v, s->cp.ice_per, t->cp.ice_per);
    visit_u64(v, s->multiple, t->multiple);
    visit_u64(v, s->multiple && s->lateral, t->multiple && t->lateral);
    visit_u64(v, s->multiple && s->volume, t->multiple && t->volume);
    visit_u64(v, (uint64_t)s->grid, (uint64_t)t->grid);
    visit_double(v, s->cp.water_cs_g, t->cp.water_cs_g);
    visit_double(v, s->cp.ice_cs_g, t->cp.ice_cs_g);
    visit_double(v, s->cp.water_gamma, t->cp.water_gamma);
    visit_double(v, s->cp.ice_gamma, t->cp.ice_gamma);
    visit_double(v, s->epsilon, t->epsilon);
    visit_u64(v, (uint64_t)(int64_t)s->substeps, (uint64_t)(int64_t)t->substeps);
}

bool light_key_equal(const struct light_key *a, const struct light_key *b)
{
    struct visit v = {.hash = 14695981039346656037ull, .other = b, .equal = true};
    visit_key(&v, a);
    return v.equal;
}

uint64_t light_key_hash(const struct light_key *k)
{
    struct visit v = {.hash = 14695981039346656037ull, .other = NULL, .equal = true};
    visit_key(&v, k);
    return v.hash;
}

void light_cache_init(struct light_cache *c)
{
    memset(c, 0, sizeof(*c));
}

bool light_cache_stale(const struct light_cache *c, const struct light_key *k)
{
    return !c->valid || light_key_hash(k) != c->hash || !light_key_equal(k, &c->key);
}

void light_cache_built(struct light_cache *c, const struct light_key *k, double ms)
{
    c->valid = true;
    c->key = *k;
    c->hash = light_key_hash(k);
    c->builds++;
    c->last_ms = ms;
    c->total_ms += ms;
}

void light_cache_invalidate(struct light_cache *c)
{
    c->valid = false;
}

bool light_map_update(const struct ext_volume *vol, const struct light_key *k,
                      struct light_cache *cache, struct light_map *map,
                      struct light_compressed *compressed, bool *built)
{
    *built = false;
    if (!light_cache_stale(cache, k))
        return true;
    double t0 = time_now_ms();
    if (!light_map_build(vol, k->sun, &k->settings, map)) {
        light_cache_invalidate(cache);
        return false;
    }
    if (compressed) {
        light_compressed_finish(compressed);
        if (!light_compressed_build(map, k->settings.epsilon, compressed)) {
            light_cache_invalidate(cache);
            return false;
        }
    }
    light_cache_built(cache, k, time_now_ms() - t0);
    *built = true;
    return true;
}
