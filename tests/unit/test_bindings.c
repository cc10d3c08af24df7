/* shaders/bindings.h: the binding points C and GLSL share.  The names that meet in one
 * program differ and fit the limits every OpenGL 4.5 driver has; the header holds nothing but
 * #define lines and comments; no shader declares, and no C bind call passes, a bare number. */
#include "testutil.h"

#include <ctype.h>
#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "shaders/bindings.h"

/* OpenGL 4.5's minimum maxima: GL_MAX_COMPUTE_TEXTURE_IMAGE_UNITS (and the fragment stage's),
 * GL_MAX_IMAGE_UNITS, GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS (and the fragment stage's). */
#define MIN_TEXTURE_UNITS 16
#define MIN_IMAGE_UNITS 8
#define MIN_STORAGE_BLOCKS 8

static void assert_distinct_below(const char *what, const int *v, int n, int limit)
{
    for (int i = 0; i < n; i++) {
        if (v[i] < 0 || v[i] >= limit)
            fail_msg("%s: binding %d is outside [0, %d)", what, v[i], limit);
        for (int j = 0; j < i; j++) {
            if (v[i] == v[j])
                fail_msg("%s: binding %d is used twice", what, v[i]);
        }
    }
}

#define DISTINCT(what, limit, ...)                                                             \
    do {                                                                                       \
        const int v_[] = {__VA_ARGS__};                                                        \
        assert_distinct_below(what, v_, (int)(sizeof(v_) / sizeof(v_[0])), limit);             \
    } while (0)

static void test_programs_do_not_collide(void **state)
{
    /* The eye pass: its own units, a light map pair's, and the opaque pass's mesh texture,
     * which renderer_draw binds between the eye pass's binds and its dispatch. */
    DISTINCT("eye pass textures", MIN_TEXTURE_UNITS, BIND_EYE_TEX_BETA, BIND_EYE_TEX_PHASE,
             BIND_EYE_TEX_OPAQUE_COLOR, BIND_EYE_TEX_OPAQUE_DISTANCE, BIND_EYE_TEX_TINT,
             BIND_EYE_TEX_BETA_NEXT, BIND_LIGHTMAP_TEX_LIGHT, BIND_LIGHTMAP_TEX_LIGHT_NEXT,
             BIND_LIGHTMAP_TEX_DIFFUSE, BIND_LIGHTMAP_TEX_DIFFUSE_NEXT, BIND_OPAQUE_TEX_MESH,
             BIND_EYE_TEX_LAYERS, BIND_EYE_TEX_LAYER_LUT, BIND_EYE_TEX_SLICES);
    DISTINCT("eye pass images", MIN_IMAGE_UNITS, BIND_EYE_IMG_OUT);
    DISTINCT("eye pass buffers", MIN_STORAGE_BLOCKS, BIND_LIGHTMAP_BUF_COLUMNS,
             BIND_LIGHTMAP_BUF_NODES, BIND_LIGHTMAP_BUF_COLUMNS_NEXT,
             BIND_LIGHTMAP_BUF_NODES_NEXT, BIND_EYE_BUF_CELLS, BIND_EYE_BUF_COUNTERS,
             BIND_EYE_BUF_RAYS);
    DISTINCT("macro cell textures", MIN_TEXTURE_UNITS, BIND_CELLS_TEX_BETA,
             BIND_CELLS_TEX_BETA_NEXT);
    DISTINCT("macro cell buffers", MIN_STORAGE_BLOCKS, BIND_CELLS_BUF_CELLS);
    DISTINCT("opaque pass textures", MIN_TEXTURE_UNITS, BIND_OPAQUE_TEX_MESH,
             BIND_LIGHTMAP_TEX_LIGHT, BIND_LIGHTMAP_TEX_LIGHT_NEXT, BIND_LIGHTMAP_TEX_DIFFUSE,
             BIND_LIGHTMAP_TEX_DIFFUSE_NEXT);
    DISTINCT("tone mapping images", MIN_IMAGE_UNITS, BIND_TONEMAP_IMG_IN, BIND_TONEMAP_IMG_OUT);
    DISTINCT("tone mapping buffers", MIN_STORAGE_BLOCKS, BIND_TONEMAP_BUF_NONFINITE);
    DISTINCT("slice pass textures", MIN_TEXTURE_UNITS, BIND_SLICES_TEX_BETA,
             BIND_SLICES_TEX_RATES);
    DISTINCT("slice pass images", MIN_IMAGE_UNITS, BIND_SLICES_IMG_SLICE);
    DISTINCT("slice pass buffers", MIN_STORAGE_BLOCKS, BIND_SLICES_BUF_CELLS);
    DISTINCT("light build textures", MIN_TEXTURE_UNITS, BIND_BUILD_TEX_SLICE);
    DISTINCT("light build images", MIN_IMAGE_UNITS, BIND_BUILD_IMG_LIGHT);
    DISTINCT("diffuse pass images", MIN_IMAGE_UNITS, BIND_DIFFUSE_IMG_LIGHT,
             BIND_DIFFUSE_IMG_SLICE, BIND_DIFFUSE_IMG_ADDING, BIND_DIFFUSE_IMG_DIFFUSE);
    DISTINCT("compression images", MIN_IMAGE_UNITS, BIND_COMPRESS_IMG_VALUES);
    DISTINCT("compression buffers", MIN_STORAGE_BLOCKS, BIND_COMPRESS_BUF_COLUMNS,
             BIND_COMPRESS_BUF_NODES);
    DISTINCT("scan buffers", MIN_STORAGE_BLOCKS, BIND_SCAN_BUF_COLUMNS);
    DISTINCT("volume pass textures", MIN_TEXTURE_UNITS, BIND_VOLUME_TEX_BETA,
             BIND_VOLUME_TEX_LIGHT);
    DISTINCT("volume pass images", MIN_IMAGE_UNITS, BIND_VOLUME_IMG_FIELD);
    DISTINCT("volume pass buffers", MIN_STORAGE_BLOCKS, BIND_VOLUME_BUF_TERMS,
             BIND_VOLUME_BUF_SYSTEM, BIND_VOLUME_BUF_VECTORS, BIND_VOLUME_BUF_SCALARS);
    DISTINCT("lateral pass textures", MIN_TEXTURE_UNITS, BIND_LATERAL_TEX_BETA);
    DISTINCT("lateral pass images", MIN_IMAGE_UNITS, BIND_LATERAL_IMG_RATES);
    DISTINCT("lateral pass buffers", MIN_STORAGE_BLOCKS, BIND_LATERAL_BUF_CELLS);
    DISTINCT("peak textures", MIN_TEXTURE_UNITS, BIND_PEAK_TEX_VOLUME);
    DISTINCT("peak images", MIN_IMAGE_UNITS, BIND_PEAK_IMG_OUT);
    DISTINCT("compose textures", MIN_TEXTURE_UNITS, BIND_COMPOSE_TEX_LEFT,
             BIND_COMPOSE_TEX_RIGHT);
    DISTINCT("compose images", MIN_IMAGE_UNITS, BIND_COMPOSE_IMG_OUT);
    DISTINCT("warp textures", MIN_TEXTURE_UNITS, BIND_WARP_TEX_EYE);
    DISTINCT("warp images", MIN_IMAGE_UNITS, BIND_WARP_IMG_OUT);
}

/* The names bindings.h defines, read from the file (not from the preprocessor), so that the
 * checks below see what a shader sees. */
struct names {
    char name[64][64];
    int count;
};

static bool is_ident(int c)
{
    return isalnum(c) || c == '_';
}

/* Blanks out C and C++ comments (keeping newlines) so the scans below see code only. */
static void strip_comments(char *s)
{
    for (char *p = s; *p; p++) {
        if (p[0] == '/' && p[1] == '/') {
            while (*p && *p != '\n')
                *p++ = ' ';
            if (!*p)
                break;
        } else if (p[0] == '/' && p[1] == '*') {
            char *end = strstr(p + 2, "*/");
            char *stop = end ? end + 2 : p + strlen(p);
            for (; p < stop; p++) {
                if (*p != '\n')
                    *p = ' ';
            }
            p--;
        }
    }
}

static char *read_text(const char *path)
{
    char *text = file_read_all(path, NULL);
    if (!text)
        fail_msg("%s: cannot be read", path);
    return text;
}

static void read_names(struct names *n)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/shaders/bindings.h", ANVIL_SOURCE_DIR);
    char *text = read_text(path);
    strip_comments(text);
    memset(n, 0, sizeof(*n));
    int line = 1;
    for (char *p = text; *p; line++) {
        char *end = strchr(p, '\n');
        if (end)
            *end = '\0';
        char name[64];
        int value, used = 0;
        const char *q = p;
        while (*q == ' ')
            q++;
        if (*q) {
            /* Only "#define BIND_NAME N": valid C and valid GLSL. */
            if (sscanf(q, "#define %63s %d %n", name, &value, &used) != 2 || q[used] != '\0' ||
                strncmp(name, "BIND_", 5) != 0)
                fail_msg("shaders/bindings.h:%d: expected only #define BIND_NAME N: %s", line,
                         q);
            assert_true(n->count < 64);
            snprintf(n->name[n->count++], sizeof(n->name[0]), "%s", name);
        }
        if (!end)
            break;
        p = end + 1;
    }
    free(text);
    assert_true(n->count >= 30); /* the header was read, not an empty file */
}

static bool defined(const struct names *n, const char *name, size_t len)
{
    for (int i = 0; i < n->count; i++) {
        if (strlen(n->name[i]) == len && strncmp(n->name[i], name, len) == 0)
            return true;
    }
    return false;
}

static int line_of(const char *text, const char *at)
{
    int line = 1;
    for (const char *c = text; c < at; c++)
        line += *c == '\n';
    return line;
}

/* Counts in *SEEN every `binding = X` in the file at PATH; returns how many of them do not
 * name a BIND_* from bindings.h (each reported). */
static int check_shader(const char *path, const struct names *n, int *seen)
{
    char *text = read_text(path);
    strip_comments(text);
    int bad = 0;
    for (char *p = strstr(text, "binding"); p; p = strstr(p + 1, "binding")) {
        if ((p > text && is_ident(p[-1])) || is_ident(p[7]))
            continue;
        const char *q = p + 7;
        while (*q == ' ' || *q == '\t')
            q++;
        if (*q != '=')
            continue;
        q++;
        while (*q == ' ' || *q == '\t')
            q++;
        size_t len = 0;
        while (is_ident(q[len]))
            len++;
        (*seen)++;
        if (len == 0 || isdigit((unsigned char)q[0]) || !defined(n, q, len)) {
            print_error("%s:%d: binding = %.*s: expected a BIND_* name from "
                        "shaders/bindings.h\n",
                        path, line_of(text, p), (int)(len ? len : 1), q);
            bad++;
        }
    }
    free(text);
    return bad;
}

static bool shader_file(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot && (!strcmp(dot, ".comp") || !strcmp(dot, ".glsl") || !strcmp(dot, ".frag") ||
                   !strcmp(dot, ".vert"));
}

static void test_shaders_use_names(void **state)
{
    struct names n;
    read_names(&n);
    char dir[1024];
    snprintf(dir, sizeof(dir), "%s/shaders", ANVIL_SOURCE_DIR);
    DIR *d = opendir(dir);
    assert_non_null(d);
    int files = 0, seen = 0, bad = 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (!shader_file(e->d_name))
            continue;
        char path[2048];
        snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
        bad += check_shader(path, &n, &seen);
        files++;
    }
    closedir(d);
    assert_int_equal(bad, 0);
    /* The shaders were found: there are ten files and 33 bindings as this test is written. */
    assert_true(files >= 10);
    assert_true(seen >= 30);
}

/* The shader scan finds a bare number and a name bindings.h lacks. */
static void test_shader_scan_finds_numbers(void **state)
{
    struct names n;
    read_names(&n);
    int seen = 0;
    const char *bad = "layout(binding = BIND_EYE_TEX_BETA) uniform sampler3D a;\n"
                      "// layout(binding = 4) in a comment is fine\n"
                      "layout(rgba32f, binding=3) uniform image2D b;\n"
                      "layout(std430, binding = BIND_NOT_IN_THE_HEADER) buffer c { float d[]; };\n";
    assert_int_equal(check_shader(test_write_file("bad.comp", bad), &n, &seen), 2);
    assert_int_equal(seen, 3);
}

/* Counts in *SEEN the gpu_*_bind calls in the C file at PATH; returns how many of them pass
 * a unit (the second argument) holding a bare number (each reported). */
static int check_c_file(const char *path, int *seen)
{
    static const char *const calls[] = {"gpu_texture_bind(", "gpu_image_bind(",
                                        "gpu_image_bind_rw(", "gpu_buffer_bind("};
    char *text = read_text(path);
    strip_comments(text);
    int bad = 0;
    for (size_t c = 0; c < sizeof(calls) / sizeof(calls[0]); c++) {
        for (char *p = strstr(text, calls[c]); p; p = strstr(p + 1, calls[c])) {
            if (p > text && is_ident(p[-1]))
                continue;
            /* The arguments' top-level commas, up to the closing parenthesis. */
            const char *comma[3] = {NULL, NULL, NULL}, *close = NULL;
            int depth = 0, commas = 0;
            for (const char *q = p + strlen(calls[c]); *q && !close; q++) {
                if (*q == '(' || *q == '[')
                    depth++;
                else if ((*q == ')' || *q == ']') && depth > 0)
                    depth--;
                else if (*q == ')')
                    close = q;
                else if (*q == ',' && depth == 0 && commas < 3)
                    comma[commas++] = q;
            }
            if (!close || commas < 1)
                continue;
            const char *start = comma[0] + 1, *end = commas > 1 ? comma[1] : close;
            (*seen)++;
            for (const char *t = start; t < end; t++) {
                if (isdigit((unsigned char)*t) && !is_ident(t[-1])) {
                    print_error("%s:%d: %.*s: the unit is a bare number; use a BIND_* name "
                                "from shaders/bindings.h\n",
                                path, line_of(text, p), (int)(close - p + 1), p);
                    bad++;
                    break;
                }
            }
        }
    }
    free(text);
    return bad;
}

static void test_c_binds_use_names(void **state)
{
    char src[1024];
    snprintf(src, sizeof(src), "%s/src", ANVIL_SOURCE_DIR);
    DIR *parts = opendir(src);
    assert_non_null(parts);
    int seen = 0, bad = 0;
    for (struct dirent *p; (p = readdir(parts));) {
        if (p->d_name[0] == '.')
            continue;
        char dir[2048];
        snprintf(dir, sizeof(dir), "%s/%s", src, p->d_name);
        DIR *d = opendir(dir);
        if (!d)
            continue;
        for (struct dirent *e; (e = readdir(d));) {
            size_t len = strlen(e->d_name);
            if (len < 3 || strcmp(e->d_name + len - 2, ".c") != 0)
                continue;
            char path[4096];
            snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
            bad += check_c_file(path, &seen);
        }
        closedir(d);
    }
    closedir(parts);
    assert_int_equal(bad, 0);
    /* The renderer, the light map, the displays: a couple of dozen calls in all. */
    assert_true(seen >= 25);
}

/* The C scan finds a bare number wherever it is in the unit argument, and only there. */
static void test_c_scan_finds_numbers(void **state)
{
    int seen = 0;
    const char *bad = "void f(void)\n{\n    gpu_texture_bind(&t, 3);\n"
                      "    gpu_image_bind(o, x ? 1 : BIND_A, true);\n"
                      "    gpu_buffer_bind(b, (BIND_B + 2));\n}\n";
    assert_int_equal(check_c_file(test_write_file("bad.c", bad), &seen), 3);
    assert_int_equal(seen, 3);
    seen = 0;
    const char *good = "void f(void)\n{\n    gpu_texture_bind(&t[2], BIND_EYE_TEX_BETA);\n"
                       "    gpu_buffer_bind(f(1, 2), next ? BIND_X2 : BIND_X); /* 3 */\n"
                       "    gpu_image_bind(o, BIND_C, g(4));\n}\n";
    assert_int_equal(check_c_file(test_write_file("good.c", good), &seen), 0);
    assert_int_equal(seen, 3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_programs_do_not_collide),
        cmocka_unit_test(test_shaders_use_names),
        cmocka_unit_test(test_shader_scan_finds_numbers),
        cmocka_unit_test(test_c_binds_use_names),
        cmocka_unit_test(test_c_scan_finds_numbers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
