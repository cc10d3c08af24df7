/* The diffuse light volume (light/light_volume.h): closed forms of the diffusion problem it
 * solves, energy conservation with albedo 1, and the hard cases of docs/stability.md (empty,
 * optical depth 1e4, a single voxel, a grazing sun). */
#include <math.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "data/synth.h"
#include "light/light.h"
#include "light/light_volume.h"
#include "optics/optics.h"

#define PI 3.14159265358979323846

/* A synthetic scene (KIND, N voxels over EXTENT metres, optical depth TAU) with its light map
 * for the sun at AZ, EL degrees on RES nodes; forward scattering as FORWARD; mean cosine G
 * for both phases when G_SET. */
struct scene {
    struct ext_volume vol;
    struct light_settings s;
    struct light_map map;
    struct optics_params optics;
};

static void scene_init(struct scene *sc, enum synth_kind kind, const int n[3],
                       const double extent[3], double tau, double az, double el,
                       const int res[3], bool forward, bool g_set, double g)
{
    memset(sc, 0, sizeof(*sc));
    optics_params_defaults(&sc->optics);
    if (g_set)
        sc->optics.g_water = sc->optics.g_ice = g;
    struct synth_desc d = {.kind = kind,
                           .n = {n[0], n[1], n[2]},
                           .extent_m = {extent[0], extent[1], extent[2]},
                           .tau = tau};
    assert_true(synth_extinction(&d, &sc->optics, &sc->vol));
    light_settings_defaults(&sc->s);
    for (int a = 0; a < 3; a++)
        sc->s.resolution[a] = res[a];
    light_settings_set_optics(&sc->s, &sc->optics, 20.0);
    sc->s.forward = forward;
    sc->s.peripheral = forward;
    double sun[3];
    light_sun_direction(az, el, sun);
    assert_true(light_map_build(&sc->vol, sun, &sc->s, &sc->map));
}

static void scene_finish(struct scene *sc)
{
    light_map_finish(&sc->map);
    ext_volume_finish(&sc->vol);
}

static void assert_finite_and_conserving(const struct light_volume *v, double tol)
{
    size_t n = grid3_count(&v->grid);
    for (size_t c = 0; c < 4 * n; c++) {
        if (!isfinite(v->field[c]))
            fail_msg("value %zu of the field is %g", c, (double)v->field[c]);
    }
    assert_true(isfinite(v->source) && v->source >= 0.0);
    /* Albedo 1: what the beam loses leaves through the box's faces. */
    if (fabs(v->leak - v->source) > tol * v->source)
        fail_msg("source %.9g, leak %.9g", v->source, v->leak);
}

static void test_empty_volume_has_no_diffuse_light(void **state)
{
    (void)state;
    struct scene sc;
    scene_init(&sc, SYNTH_EMPTY, (int[3]){8, 8, 4}, (double[3]){8e3, 8e3, 4e3}, 0.0, 30.0, 40.0,
               (int[3]){8, 8, 8}, true, false, 0.0);
    struct light_volume v = {0};
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, NULL, &v));
    assert_int_equal(v.grid.n[0], 4);
    assert_int_equal(v.grid.n[2], 2);
    for (size_t c = 0; c < 4 * grid3_count(&v.grid); c++)
        assert_true(v.field[c] == 0.0f);
    assert_int_equal(v.iterations, 0);
    assert_true(v.source == 0.0 && v.leak == 0.0);
    light_volume_finish(&v);
    light_volume_finish(&v); /* twice, and NULL, are fine */
    light_volume_finish(NULL);
    scene_finish(&sc);
}

/* The infinite slab, sun overhead, shadow-only beam and a phase of mean cosine 0: the beam
 * loses beta e^-(beta z) at depth z and none of it drifts, so the diffusion problem is
 * -D phi'' = beta e^-(beta z), D = 1 / (3 beta), with the boundary condition phi -/+ R D phi' = 0
 * at the top and the bottom (R = LIGHT_VOLUME_BOUNDARY_R, 2.1312: the Milne extrapolation
 * length; Marshak's would be 2): phi = A + B z - 3 e^-(beta z),
 * B = -(3 + R + (R - 3) e^-tau) / (H + 2 R D), A = 3 + R + R D B.  The box is 100 km wide, so
 * its middle is the infinite slab. */
static void test_slab_matches_closed_form(void **state)
{
    (void)state;
    const double H = 1000.0, tau = 4.0, beta = tau / H, D = 1.0 / (3.0 * beta);
    struct scene sc;
    scene_init(&sc, SYNTH_SLAB, (int[3]){8, 8, 40}, (double[3]){1e5, 1e5, H}, tau, 0.0, 90.0,
               (int[3]){4, 4, 161}, false, true, 0.0);
    struct light_volume v = {0};
    struct light_volume_desc d = {.resolution = {8, 8, 40}, .tolerance = 1e-10};
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, &d, &v));
    assert_finite_and_conserving(&v, 1e-6);
    /* The source is what the beam lost: E (1 - e^-tau) per unit area, to the light map's
     * interpolation of e^-(beta z) between its nodes. */
    double area = 1e5 * 1e5;
    assert_float_equal(v.source / area, 1.0 - exp(-tau), 2e-3);
    const double R = LIGHT_VOLUME_BOUNDARY_R;
    double B = -(3.0 + R + (R - 3.0) * exp(-tau)) / (H + 2.0 * R * D), A = 3.0 + R + R * D * B;
    double worst = 0.0;
    for (int k = 0; k < 40; k++) {
        double zc = (k + 0.5) * H / 40.0, depth = H - zc;
        double exact = A + B * depth - 3.0 * exp(-beta * depth);
        double p[3] = {5e4, 5e4, zc};
        float f[4];
        light_volume_sample(&v, p, f);
        worst = fmax(worst, fabs(f[0] - exact) / exact);
        /* No horizontal flux in the middle; the net flux runs up above the source's centre
         * and down below it, F = -D phi'. */
        assert_true(fabsf(f[1]) < 1e-3f * f[0] && fabsf(f[2]) < 1e-3f * f[0]);
    }
    if (worst > 0.01)
        fail_msg("fluence off the closed form by %.3g (relative)", worst);
    /* The top lets out phi / R: the flux at the topmost cell points up. */
    float top[4];
    light_volume_sample(&v, (double[3]){5e4, 5e4, H - 12.5}, top);
    assert_true(top[3] > 0.0f);
    light_volume_finish(&v);
    scene_finish(&sc);
}

/* With the default optics (forward scattering on, water and ice phases mixed by a storm's
 * species) nothing is absorbed: the net flux out of the box is the beam's loss. */
static void test_storm_conserves_energy(void **state)
{
    (void)state;
    struct scene sc;
    scene_init(&sc, SYNTH_STORM, (int[3]){32, 32, 16}, (double[3]){6e4, 6e4, 1.6e4}, 0.0,
               135.0, 35.0, (int[3]){32, 32, 32}, true, false, 0.0);
    struct light_volume v = {0};
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, &(struct light_volume_desc){
                                                                .tolerance = 1e-9},
                                   &v));
    assert_true(v.source > 0.0);
    assert_finite_and_conserving(&v, 1e-5);
    /* Light crosses columns: the clear air around the storm holds diffuse light. */
    float corner[4];
    light_volume_sample(&v, (double[3]){1e3, 1e3, 1.5e4}, corner);
    assert_true(corner[0] > 0.0f);
    light_volume_finish(&v);
    scene_finish(&sc);
}

/* A wall of cloud (2 km thick, 60 km long, 10 km high, optical depth 20 across) filling the
 * box, lit through its long face and its top by suns 44, 45 and 46 degrees up: the beam that
 * enters is all lost inside (optical depth 28 or more along the light), so the source is the
 * power that enters, E (A_face cos el + A_top sin el), whatever the light map's nodes do at the
 * face.  At 45 degrees the map's node planes fall on the face, the map's interpolation puts a
 * third of the face's drop outside the box, and the source taken from the map's fall along the
 * light inside the cells came out 0.69 of this (0.85 at 44 and 46); through the cells' faces
 * it is 0.97 - 0.98, the rest the beam that leaves through the bottom and the far face. */
static void test_source_is_what_enters_a_face(void **state)
{
    (void)state;
    const double els[3] = {44.0, 45.0, 46.0};
    double ratio[3];
    for (int e = 0; e < 3; e++) {
        struct scene sc;
        scene_init(&sc, SYNTH_SLAB, (int[3]){16, 64, 64}, (double[3]){2e3, 6e4, 1e4}, 100.0, 270.0,
                   els[e], (int[3]){64, 64, 64}, true, false, 0.0);
        struct light_volume v = {0};
        assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, NULL, &v));
        assert_finite_and_conserving(&v, 1e-5);
        double el = els[e] * PI / 180.0;
        double incident = 2e3 * 6e4 * sin(el) + 6e4 * 1e4 * cos(el);
        ratio[e] = v.source / incident;
        print_message("wall under a sun at %g degrees: source / incident %.4f\n", els[e], ratio[e]);
        if (!(ratio[e] > 0.95 && ratio[e] <= 1.0))
            fail_msg("source %.4g of an incident %.4g (%.3f)", v.source, incident, ratio[e]);
        light_volume_finish(&v);
        scene_finish(&sc);
    }
    assert_true(fabs(ratio[1] - ratio[0]) < 0.02 && fabs(ratio[1] - ratio[2]) < 0.02);
}

/* Where in a cell the beam's loss lies (light_volume_cell_source), the sun overhead on 1 km
 * voxels and 2 km cells: an opaque top layer over x < 3 km and an opaque layer under it.  The
 * top cell at x 0 - 2 km, lit through its top face, loses all of it there: its centroid at the
 * top face, half a cell up (the cell's bound).  The cell under the shadow's edge (x 2 - 4 km)
 * is lit only where its top face lies beyond x = 3 km (a third of the face's points; the
 * extinction is trilinear between voxel centres): its centroid lies up and toward +x, by about
 * a third of a cell (the face's first moment across the light: 0 if that moment were left out,
 * below 0 with its sign turned). */
static void test_source_centroid(void **state)
{
    (void)state;
    struct ext_volume vol = {0};
    struct grid3 g = {.n = {8, 8, 8}, .spacing = {1e3, 1e3, 1e3}};
    assert_true(ext_volume_init(&vol, &g));
    for (int k = 0; k < 8; k++) {
        for (int j = 0; j < 8; j++) {
            for (int i = 0; i < 8; i++) {
                bool top = k >= 6 && i < 3, under = k == 4 || k == 5;
                vol.beta[2 * grid3_index(&g, i, j, k) + 1] = top ? 0.5f : under ? 2e-3f : 0.0f;
            }
        }
    }
    struct light_settings s;
    light_settings_defaults(&s);
    struct optics_params optics;
    optics_params_defaults(&optics);
    light_settings_set_optics(&s, &optics, 20.0);
    for (int a = 0; a < 3; a++)
        s.resolution[a] = 64;
    double sun[3];
    light_sun_direction(0.0, 90.0, sun);
    struct light_map map = {0};
    assert_true(light_map_build(&vol, sun, &s, &map));
    const double dx = 2e3;
    double q0, dq[3];
    light_volume_cell_source(&vol, &map, &s, NULL, (int[3]){0, 1, 3}, &q0, dq);
    print_message("lit top cell: q0 %.4g per m, centroid (%.0f, %.0f, %.0f) m\n", q0, dq[0] / q0,
                  dq[1] / q0, dq[2] / q0);
    assert_float_equal(q0 * dx, 1.0, 0.02); /* all of the beam through its top */
    assert_true(dq[2] / q0 > 0.45 * dx && dq[2] / q0 <= 0.5 * dx);
    assert_true(fabs(dq[0]) / q0 < 0.01 * dx);
    light_volume_cell_source(&vol, &map, &s, NULL, (int[3]){1, 1, 2}, &q0, dq);
    print_message("cell under the shadow's edge: q0 %.4g per m, centroid (%.0f, %.0f, %.0f) m\n",
                  q0, dq[0] / q0, dq[1] / q0, dq[2] / q0);
    assert_true(q0 * dx > 0.1 && q0 * dx < 0.5); /* a third of the face's points lit */
    assert_true(dq[0] / q0 > 0.25 * dx && dq[0] / q0 < 0.4 * dx);
    assert_true(dq[2] / q0 > 0.05 * dx && dq[2] / q0 < 0.4 * dx);
    assert_true(fabs(dq[1]) / q0 < 0.01 * dx);
    light_map_finish(&map);
    ext_volume_finish(&vol);
}

/* Hard cases: optical depth 1e4 (every cell opaque), a single voxel, a grazing sun. */
static void test_hard_cases_stay_finite(void **state)
{
    (void)state;
    struct scene sc;
    scene_init(&sc, SYNTH_SLAB, (int[3]){8, 8, 8}, (double[3]){8e3, 8e3, 2e3}, 1e4, 60.0, 30.0,
               (int[3]){16, 16, 16}, true, false, 0.0);
    struct light_volume v = {0};
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, NULL, &v));
    assert_finite_and_conserving(&v, 1e-5);
    /* Nothing is absorbed, so through the opaque layer the fluence falls linearly (the
     * conservative diffusion solution), not exponentially: down the middle column it falls
     * from the sunlit top.  (How deep the beam seems to reach into it is the light map's
     * interpolation between its nodes, here a kilometre apart along the light.) */
    float prev = INFINITY;
    for (int k = 0; k < 8; k++) {
        float f[4];
        light_volume_sample(&v, (double[3]){4e3, 4e3, 2e3 - (k + 0.5) * 250.0}, f);
        if (!(f[0] >= 0.0f && f[0] <= prev))
            fail_msg("fluence %g at step %d below %g", (double)f[0], k, (double)prev);
        prev = f[0];
    }
    light_volume_finish(&v);
    scene_finish(&sc);

    /* One voxel lit from overhead: two cells a side (the fewest), mirror-symmetric across. */
    scene_init(&sc, SYNTH_VOXEL, (int[3]){1, 1, 1}, (double[3]){1e3, 1e3, 1e3}, 3.0, 0.0, 90.0,
               (int[3]){4, 4, 8}, true, false, 0.0);
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, NULL, &v));
    assert_int_equal(v.grid.n[0], 2);
    assert_finite_and_conserving(&v, 1e-5);
    for (int k = 0; k < 2; k++) {
        float a = v.field[4 * (0 + 4 * k)], b = v.field[4 * (3 + 4 * k)];
        assert_true(a > 0.0f);
        assert_float_equal(a, b, 1e-5 * a);
    }
    light_volume_finish(&v);
    scene_finish(&sc);

    /* A sun half a degree above the horizon on a layer. */
    scene_init(&sc, SYNTH_SLAB, (int[3]){16, 16, 4}, (double[3]){4e4, 4e4, 1e3}, 10.0, 200.0,
               0.5, (int[3]){16, 16, 16}, true, false, 0.0);
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, NULL, &v));
    assert_true(v.source > 0.0);
    assert_finite_and_conserving(&v, 1e-5);
    light_volume_finish(&v);
    scene_finish(&sc);
}

/* The bricks' preconditioner (the default) against the diagonal alone on a storm at the default
 * grid (32 x 32 x 32 cells): a third of the iterations or fewer (43 against 140 when written;
 * the bricks without the coarse correction take 77), and the same solution within the solve's
 * tolerance. */
static void test_bricks_need_fewer_iterations(void **state)
{
    (void)state;
    struct scene sc;
    scene_init(&sc, SYNTH_STORM, (int[3]){64, 64, 32}, (double[3]){6e4, 6e4, 1.6e4}, 0.0, 135.0,
               35.0, (int[3]){48, 48, 48}, true, false, 0.0);
    struct light_volume b = {0}, j = {0};
    struct light_volume_desc d = {.tolerance = 1e-8};
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, &d, &b));
    d.preconditioner = LIGHT_VOLUME_PRECOND_JACOBI;
    assert_true(light_volume_build(&sc.vol, &sc.map, &sc.s, &d, &j));
    print_message("iterations: bricks %d, Jacobi %d\n", b.iterations, j.iterations);
    assert_int_equal(b.grid.n[0], 32);
    assert_true(b.iterations > 0 && 3 * b.iterations <= j.iterations);
    size_t n = grid3_count(&b.grid);
    double phi_max = 0.0, worst = 0.0;
    for (size_t c = 0; c < n; c++)
        phi_max = fmax(phi_max, j.field[4 * c]);
    for (size_t c = 0; c < 4 * n; c++)
        worst = fmax(worst, fabs((double)b.field[c] - j.field[c]));
    print_message("largest difference %.3g of the largest phi %.3g\n", worst, phi_max);
    assert_true(phi_max > 0.5 && worst < 1e-5 * phi_max);
    assert_finite_and_conserving(&b, 1e-6);
    light_volume_finish(&b);
    light_volume_finish(&j);
    scene_finish(&sc);
}

static void test_scattered_light_toward_the_eye(void **state)
{
    (void)state;
    /* Within the cap the phase's first moment: phi + 3 g F.w. */
    const float small[4] = {1.0f, 0.05f, 0.0f, 0.0f};
    assert_float_equal(light_volume_scattered(small, 0.5f, (double[3]){1, 0, 0}), 1.075, 1e-6);
    assert_float_equal(light_volume_scattered(small, 0.5f, (double[3]){0, 1, 0}), 1.0, 1e-6);
    /* Beyond it the flux is scaled to LIGHT_VOLUME_ANISOTROPY phi. */
    const float big[4] = {2.0f, 0.0f, 0.0f, -3.0f};
    double cap = 3.0 * 0.8 * LIGHT_VOLUME_ANISOTROPY * 2.0;
    assert_float_equal(light_volume_scattered(big, 0.8f, (double[3]){0, 0, -1}), 2.0 + cap, 1e-6);
    assert_float_equal(light_volume_scattered(big, 0.8f, (double[3]){0, 0, 1}), 2.0 - cap, 1e-6);
    /* Never negative, and no flux without fluence. */
    const float none[4] = {0.0f, 1.0f, 0.0f, 0.0f}, neg[4] = {-1.0f, 0.0f, 0.0f, 0.0f};
    assert_true(light_volume_scattered(none, 0.9f, (double[3]){1, 0, 0}) == 0.0f);
    assert_true(light_volume_scattered(neg, 0.9f, (double[3]){1, 0, 0}) == 0.0f);
    /* Outside the box the field reads 0. */
    struct light_volume v = {.grid = {.n = {2, 2, 2}, .spacing = {1, 1, 1}}};
    float f[4] = {1, 1, 1, 1}, cells[32];
    for (int i = 0; i < 32; i++)
        cells[i] = 1.0f;
    v.field = cells;
    light_volume_sample(&v, (double[3]){1, 1, 2.5}, f);
    assert_true(f[0] == 0.0f && f[3] == 0.0f);
    light_volume_sample(&v, (double[3]){1, 1, 1}, f);
    assert_float_equal(f[0], 1.0, 1e-7);
}

/* The volume is part of the light map's key: switching it rebuilds; it means nothing without
 * multiple scattering. */
static void test_volume_is_in_the_key(void **state)
{
    (void)state;
    struct grid3 box = {.n = {4, 4, 4}, .spacing = {1e3, 1e3, 1e3}};
    double sun[3] = {0.3, 0.2, 0.9};
    struct light_settings a, b;
    light_settings_defaults(&a);
    a.multiple = true;
    b = a;
    b.volume = true;
    struct light_key ka, kb;
    light_key_init(&ka, &box, sun, 1, 1, &a);
    light_key_init(&kb, &box, sun, 1, 1, &b);
    assert_false(light_key_equal(&ka, &kb));
    assert_true(light_key_hash(&ka) != light_key_hash(&kb));
    a.multiple = b.multiple = false;
    light_key_init(&ka, &box, sun, 1, 1, &a);
    light_key_init(&kb, &box, sun, 1, 1, &b);
    assert_true(light_key_equal(&ka, &kb));
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_empty_volume_has_no_diffuse_light),
        cmocka_unit_test(test_slab_matches_closed_form),
        cmocka_unit_test(test_storm_conserves_energy),
        cmocka_unit_test(test_source_is_what_enters_a_face),
        cmocka_unit_test(test_source_centroid),
        cmocka_unit_test(test_hard_cases_stay_finite),
        cmocka_unit_test(test_bricks_need_fewer_iterations),
        cmocka_unit_test(test_scattered_light_toward_the_eye),
        cmocka_unit_test(test_volume_is_in_the_key),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
