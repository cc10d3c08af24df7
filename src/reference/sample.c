/*
 * reference/sample: the random numbers and the phase function sampling of the Monte Carlo
 * reference (reference.h).
 */
#include "reference/reference.h"

/* Same clamp as optics' phase functions, so sampling and evaluation agree. */
#define G_MAX 0.999

/* ---- random numbers ---------------------------------------------------------------------- */

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static inline uint64_t rotl(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

void reference_rng_seed(struct reference_rng *rng, uint64_t seed, uint64_t stream)
{
    /* Mix the stream into the seed first so that neighbouring (seed, stream) pairs give
     * unrelated states; splitmix64 then fills the four words (never all zero). */
    uint64_t x = seed;
    uint64_t h = splitmix64(&x) ^ (stream * 0xd1342543de82ef95ull);
    x = h;
    for (int i = 0; i < 4; i++)
        rng->s[i] = splitmix64(&x);
}

uint64_t reference_rng_next(struct reference_rng *rng)
{
    uint64_t *s = rng->s;
    uint64_t result = rotl(s[1] * 5, 7) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

double reference_rng_uniform(struct reference_rng *rng)
{
    return (double)(reference_rng_next(rng) >> 11) * 0x1.0p-53;
}


/* ---- phase sampling ---------------------------------------------------------------------- */

static double clamp_g(double g)
{
    return g > G_MAX ? G_MAX : g < -G_MAX ? -G_MAX : g;
}

double reference_sample_hg(double g, struct reference_rng *rng)
{
    g = clamp_g(g);
    /* Elek eq. 2.5 (with 2g, not |2g|, so that negative g scatters backward):
     *   mu = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g xi))^2) / (2 g).
     * With a = 1 - 2 xi and D = 1 - g a, expanding the numerator over D^2 divides out the
     * factor g exactly:
     *   mu = (-a + g (3 + a^2) / 2 - g^2 a + g^3 (a^2 - 1) / 2) / D^2,
     * which is the isotropic mu = 2 xi - 1 at g = 0 and has no cancellation near it. */
    double a = 1.0 - 2.0 * reference_rng_uniform(rng);
    double d = 1.0 - g * a;
    double num = -a + g * (0.5 * (3.0 + a * a) + g * (-a + 0.5 * g * (a * a - 1.0)));
    double mu = num / (d * d);
    return mu > 1.0 ? 1.0 : mu < -1.0 ? -1.0 : mu;
}

double reference_sample_cs(double g, struct reference_rng *rng)
{
    /* p_CS(mu) = p_HG(mu) * 3 (1 + mu^2) / (2 (2 + g^2)) <= p_HG(mu) * 3 / (2 + g^2), so
     * HG samples accepted with probability (1 + mu^2) / 2 are exact CS samples. */
    for (;;) {
        double mu = reference_sample_hg(g, rng);
        if (2.0 * reference_rng_uniform(rng) < 1.0 + mu * mu)
            return mu;
    }
}
