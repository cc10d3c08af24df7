/* Animations through the program: every step of a series written equals a still render of
 * that step; in-between frames blend; a movie decodes with the right frames, size and rate and
 * its first frame matches the PNG's colours within codec error; a camera path meets its keys
 * exactly at their times. */
#include <glob.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libswscale/swscale.h>

#include "testutil.h"

#include "gpu/gpu.h"
#include "render/image.h"

static const char *anvil;
static char dir[512], cfg[600];
static const char *size = "--set render.width=64 --set render.height=48";

static void run(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void run(const char *fmt, ...)
{
    char args[2048], cmd[3072];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof(args), fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof(cmd), "cd '%s' && '%s' --quiet %s", dir, anvil, args);
    if (system(cmd) != 0)
        fail_msg("failed: %s", cmd);
}

static void read_pfm(const char *name, struct image *img)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    if (!image_read_pfm(path, img))
        fail_msg("%s was not written", path);
}

static bool same(const struct image *a, const struct image *b)
{
    return a->width == b->width && a->height == b->height &&
           memcmp(a->rgba, b->rgba, sizeof(float) * 4 * (size_t)a->width * a->height) == 0;
}

/* Whether a file NAME (a glob pattern) is in the test folder. */
static bool exists(const char *name)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    glob_t g;
    bool found = glob(path, 0, NULL, &g) == 0 && g.gl_pathc > 0;
    globfree(&g);
    return found;
}

static void test_steps_equal_still_renders(void **state)
{
    run("render %s %s --frames all -o 'f-%%03d.pfm'", cfg, size);
    assert_false(exists("f-004.pfm"));
    for (int k = 0; k < 4; k++) {
        char name[64];
        run("render %s %s --set data.step=%d -o still-%d.pfm", cfg, size, k, k);
        snprintf(name, sizeof(name), "f-%03d.pfm", k);
        struct image frame, still;
        read_pfm(name, &frame);
        snprintf(name, sizeof(name), "still-%d.pfm", k);
        read_pfm(name, &still);
        if (!same(&frame, &still))
            fail_msg("frame %d differs from a still render of step %d", k, k);
        image_finish(&frame);
        image_finish(&still);
    }
    /* A range with a stride. */
    run("render %s %s --frames 1:3:2 -o 'r-%%d.pfm'", cfg, size);
    struct image r1, s3;
    read_pfm("r-1.pfm", &r1);
    read_pfm("still-3.pfm", &s3);
    assert_true(same(&r1, &s3));
    assert_false(exists("r-2.pfm"));
    image_finish(&r1);
    image_finish(&s3);
}

/* playback.speed = 2 steps/s, --fps 4: a frame every half step, the odd ones blended. */
static void test_inbetweens_blend(void **state)
{
    run("render %s %s --fps 4 -o 'b-%%02d.pfm'", cfg, size);
    assert_true(exists("b-06.pfm"));
    assert_false(exists("b-07.pfm")); /* steps 0..3 at 0.5 a frame: 7 frames */
    struct image f0, f1, f2, s1;
    read_pfm("b-00.pfm", &f0);
    read_pfm("b-01.pfm", &f1);
    read_pfm("b-02.pfm", &f2);
    read_pfm("still-1.pfm", &s1);
    assert_true(same(&f2, &s1)); /* whole steps are the steps */
    assert_false(same(&f1, &f0));
    assert_false(same(&f1, &f2));
    /* Between: on average the blended frame is nearer the mean of its neighbours than either. */
    double d_mean = 0.0, d0 = 0.0, d2 = 0.0;
    for (int i = 0; i < f1.width * f1.height * 4; i++) {
        double m = 0.5 * (f0.rgba[i] + f2.rgba[i]);
        d_mean += fabs(f1.rgba[i] - m);
        d0 += fabs(f1.rgba[i] - f0.rgba[i]);
        d2 += fabs(f1.rgba[i] - f2.rgba[i]);
    }
    assert_true(d_mean < d0 && d_mean < d2);
    image_finish(&f0);
    image_finish(&f1);
    image_finish(&f2);
    image_finish(&s1);
}

/* Decodes every frame of PATH; the first into RGB24 (top row first) in FIRST. */
static int decode(const char *path, int *w, int *h, AVRational *rate, uint8_t **first)
{
    AVFormatContext *fc = NULL;
    assert_int_equal(avformat_open_input(&fc, path, NULL, NULL), 0);
    assert_true(avformat_find_stream_info(fc, NULL) >= 0);
    int si = av_find_best_stream(fc, AVMEDIA_TYPE_VIDEO, -1, -1, NULL, 0);
    assert_true(si >= 0);
    AVStream *st = fc->streams[si];
    const AVCodec *codec = avcodec_find_decoder(st->codecpar->codec_id);
    assert_non_null(codec);
    AVCodecContext *dc = avcodec_alloc_context3(codec);
    avcodec_parameters_to_context(dc, st->codecpar);
    assert_int_equal(avcodec_open2(dc, codec, NULL), 0);
    *w = dc->width;
    *h = dc->height;
    *rate = st->avg_frame_rate;
    assert_int_equal(st->codecpar->color_primaries, AVCOL_PRI_BT709);
    assert_int_equal(st->codecpar->color_space, AVCOL_SPC_BT709);
    assert_int_equal(st->codecpar->color_range, AVCOL_RANGE_MPEG);
    AVPacket *pkt = av_packet_alloc();
    AVFrame *frame = av_frame_alloc();
    int frames = 0;
    *first = NULL;
    for (bool flushing = false;;) {
        int rc = flushing ? avcodec_send_packet(dc, NULL) : 0;
        if (!flushing) {
            if (av_read_frame(fc, pkt) < 0) {
                flushing = true;
                continue;
            }
            if (pkt->stream_index == si)
                avcodec_send_packet(dc, pkt);
            av_packet_unref(pkt);
        }
        while ((rc = avcodec_receive_frame(dc, frame)) == 0) {
            if (frames == 0) {
                *first = malloc((size_t)*w * *h * 3);
                struct SwsContext *sws =
                    sws_getContext(*w, *h, frame->format, *w, *h, AV_PIX_FMT_RGB24,
                                   SWS_BICUBIC | SWS_ACCURATE_RND, NULL, NULL, NULL);
                sws_setColorspaceDetails(sws, sws_getCoefficients(SWS_CS_ITU709), 0,
                                         sws_getCoefficients(SWS_CS_ITU709), 1, 0, 1 << 16,
                                         1 << 16);
                uint8_t *dst[1] = {*first};
                int stride[1] = {3 * *w};
                sws_scale(sws, (const uint8_t *const *)frame->data, frame->linesize, 0, *h, dst,
                          stride);
                sws_freeContext(sws);
            }
            frames++;
        }
        if (flushing)
            break;
    }
    av_frame_free(&frame);
    av_packet_free(&pkt);
    avcodec_free_context(&dc);
    avformat_close_input(&fc);
    return frames;
}

static void test_movie(void **state)
{
    run("render %s %s --fps 8 -o storm.mp4", cfg, size);
    assert_false(exists("storm.mp4.tmp*")); /* no temporary file left */
    char path[1024];
    snprintf(path, sizeof(path), "%s/storm.mp4", dir);
    int w, h;
    AVRational rate;
    uint8_t *rgb;
    int frames = decode(path, &w, &h, &rate, &rgb);
    assert_int_equal(frames, 13); /* 3 steps at 4 frames a step, and the last */
    assert_int_equal(w, 64);
    assert_int_equal(h, 48);
    assert_int_equal(rate.num, 8);
    assert_int_equal(rate.den, 1);
    /* The first frame: the still render of step 0, tone-mapped as PNG, within codec error. */
    struct image still;
    read_pfm("still-0.pfm", &still);
    double sum = 0.0, worst = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++) {
                double want = image_tonemap(still.rgba[4 * ((size_t)(h - 1 - y) * w + x) + c],
                                            1.0f);
                double got = rgb[3 * ((size_t)y * w + x) + c];
                sum += fabs(got - want);
                worst = fmax(worst, fabs(got - want));
            }
    double mean = sum / (3.0 * w * h);
    printf("movie frame 0 against the PNG: mean %.2f, worst %.0f levels of 255\n", mean, worst);
    assert_true(mean < 4.0);
    free(rgb);
    image_finish(&still);
}

static void test_camera_path_meets_keys(void **state)
{
    FILE *f = fopen(test_tmp_path("fly.cfg"), "w");
    fprintf(f, "camera_path = { keys = (\n"
               "  { time = 0.0; position = [-6.0, -10.0, 6.0]; target = [8.0, 8.0, 3.0]; },\n"
               "  { time = 2.0; position = [20.0, -8.0, 5.0]; target = [8.0, 8.0, 2.0]; fov = 40.0; },\n"
               "  { time = 5.0; position = [24.0, 20.0, 9.0]; target = [8.0, 8.0, 0.0]; fov = 60.0; }\n"
               "); };\n");
    fclose(f);
    run("render %s %s --path fly.cfg --fps 2 -o 'p-%%02d.pfm'", cfg, size);
    assert_true(exists("p-10.pfm"));
    assert_false(exists("p-11.pfm")); /* 0 .. 5 s at 2 frames a second */
    run("render %s %s --set 'camera.position=[20.0,-8.0,5.0]' --set 'camera.target=[8.0,8.0,2.0]' "
        "--set camera.fov=40 -o key1.pfm",
        cfg, size);
    run("render %s %s --set 'camera.position=[24.0,20.0,9.0]' --set 'camera.target=[8.0,8.0,0.0]' "
        "--set camera.fov=60 -o key2.pfm",
        cfg, size);
    struct image p4, p10, k1, k2, p5;
    read_pfm("p-04.pfm", &p4);
    read_pfm("key1.pfm", &k1);
    read_pfm("p-10.pfm", &p10);
    read_pfm("key2.pfm", &k2);
    read_pfm("p-05.pfm", &p5);
    assert_true(same(&p4, &k1));
    assert_true(same(&p10, &k2));
    assert_false(same(&p5, &k1)); /* and it moves on */
    image_finish(&p4);
    image_finish(&p5);
    image_finish(&p10);
    image_finish(&k1);
    image_finish(&k2);
}

static void test_display_sequences(void **state)
{
    run("render %s --set render.height=24 --display " ANVIL_SOURCE_DIR "/displays/desktop-stereo.cfg "
        "--set display.mode=side-by-side --frames 0:1 -o 'd-%%d.png'", cfg);
    assert_true(exists("screen-left-d-0.png") && exists("screen-right-d-1.png"));
    assert_true(exists("screen-d-1.png")); /* the side-by-side pair */
    run("render %s --set render.height=24 --display " ANVIL_SOURCE_DIR "/displays/desktop-stereo.cfg "
        "--frames 0:1 -o 'eyes.mp4'", cfg);
    assert_true(exists("eyes-screen-left.mp4") && exists("eyes-screen.mp4"));
}

int main(void)
{
    gpu_context_destroy(test_gl_context_or_skip());
    anvil = getenv("ANVIL_BIN");
    if (!anvil)
        return TEST_SKIP;
    snprintf(dir, sizeof(dir), "%s", test_tmpdir());
    snprintf(cfg, sizeof(cfg), "series.cfg");
    run("synth -o series.nc --steps 4 --size 16x16x8 --extent 16x16x8 >/dev/null");
    FILE *f = fopen(test_tmp_path("series.cfg"), "w");
    fprintf(f, "scene = { kind = \"data\"; };\n"
               "data = { format = \"wrf\"; files = [\"series.nc\"]; };\n"
               "camera = { position = [-6.0, -10.0, 6.0]; target = [8.0, 8.0, 3.0]; };\n"
               "lightmap = { resolution = [24, 24, 24]; };\n");
    fclose(f);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_steps_equal_still_renders),
        cmocka_unit_test(test_inbetweens_blend),
        cmocka_unit_test(test_movie),
        cmocka_unit_test(test_camera_path_meets_keys),
        cmocka_unit_test(test_display_sequences),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
