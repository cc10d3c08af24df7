/* Movies through FFmpeg: sRGB frames -> BT.709 limited-range 4:2:0 -> an encoder -> a muxer. */
#include "render/video.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/imgutils.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>

#include "common/fatal.h"
#include "common/log.h"

struct video_writer {
    char path[1024], target[4096], tmp[4200];
    AVFormatContext *oc;
    AVCodecContext *enc;
    AVStream *st;
    AVFrame *frame;
    AVPacket *pkt;
    struct SwsContext *sws;
    uint8_t *rgb; /* one frame, top row first */
    int width, height, frames; /* the movie's: the frames' rounded up to even */
    int in_width, in_height;   /* the frames' */
    bool header_written;
};

static const char *av_text(int err, char *buf, size_t size)
{
    av_strerror(err, buf, size);
    return buf;
}

bool video_path_supported(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return false;
    /* FFmpeg guesses image muxers for .png and friends: those are not movies here. */
    static const char *const stills[] = {".png", ".pfm", ".jpg", ".jpeg", ".bmp", ".tif",
                                         ".tiff", ".gif", ".webp"};
    for (size_t i = 0; i < sizeof(stills) / sizeof(stills[0]); i++)
        if (strcasecmp(dot, stills[i]) == 0)
            return false;
    av_log_set_level(AV_LOG_ERROR);
    const AVOutputFormat *f = av_guess_format(NULL, path, NULL);
    return f && f->video_codec != AV_CODEC_ID_NONE && !(f->flags & AVFMT_NOFILE);
}

const char *video_encoders(void)
{
    static char list[512];
    if (list[0])
        return list;
    void *it = NULL;
    const AVCodec *c;
    size_t len = 0;
    static const char *const wanted[] = {"libx264", "libx265", "libvpx-vp9", "libaom-av1",
                                         "mpeg4", "libxvid", "mjpeg", "ffv1"};
    for (size_t w = 0; w < sizeof(wanted) / sizeof(wanted[0]); w++) {
        it = NULL;
        while ((c = av_codec_iterate(&it))) {
            if (av_codec_is_encoder(c) && c->type == AVMEDIA_TYPE_VIDEO &&
                strcmp(c->name, wanted[w]) == 0 && len + strlen(c->name) + 2 < sizeof(list))
                len += (size_t)snprintf(list + len, sizeof(list) - len, "%s%s", len ? " " : "",
                                        c->name);
        }
    }
    return list;
}

static const AVCodec *pick_encoder(const AVOutputFormat *fmt, const char *name, const char *path)
{
    if (name) {
        const AVCodec *c = avcodec_find_encoder_by_name(name);
        if (!c || c->type != AVMEDIA_TYPE_VIDEO) {
            log_error("%s: --codec %s: no such video encoder in this FFmpeg (it has: %s)", path,
                      name, video_encoders());
            return NULL;
        }
        if (avformat_query_codec(fmt, c->id, FF_COMPLIANCE_NORMAL) != 1) {
            log_error("%s: --codec %s: the %s container cannot hold it", path, name, fmt->name);
            return NULL;
        }
        return c;
    }
    const AVCodec *c = avcodec_find_encoder(AV_CODEC_ID_H264);
    if (c && avformat_query_codec(fmt, AV_CODEC_ID_H264, FF_COMPLIANCE_NORMAL) == 1)
        return c;
    c = avcodec_find_encoder(fmt->video_codec);
    if (!c)
        log_error("%s: this FFmpeg has no encoder for a %s movie", path, fmt->name);
    return c;
}

static void destroy(struct video_writer *v)
{
    if (v->oc && v->oc->pb)
        avio_closep(&v->oc->pb);
    avformat_free_context(v->oc);
    avcodec_free_context(&v->enc);
    av_frame_free(&v->frame);
    av_packet_free(&v->pkt);
    sws_freeContext(v->sws);
    free(v->rgb);
    free(v);
}

bool video_check(const char *path, const char *codec)
{
    av_log_set_level(AV_LOG_ERROR);
    const AVOutputFormat *fmt = av_guess_format(NULL, path, NULL);
    if (!fmt || fmt->video_codec == AV_CODEC_ID_NONE) {
        log_error("%s: not a movie name: expected .mp4, .mkv, .mov or another video container",
                  path);
        return false;
    }
    return pick_encoder(fmt, codec, path) != NULL;
}

struct video_writer *video_open(const char *path, const struct video_desc *d)
{
    char err[128];
    if (d->width < 1 || d->height < 1 || d->width > 16384 || d->height > 16384) {
        log_error("%s: expected frames of 1 to 16384 pixels a side, got %dx%d", path, d->width,
                  d->height);
        return NULL;
    }
    if (d->fps < 1 || d->fps > 1000) {
        log_error("%s: expected a frame rate in [1, 1000], got %d", path, d->fps);
        return NULL;
    }
    av_log_set_level(AV_LOG_ERROR);
    const AVOutputFormat *fmt = av_guess_format(NULL, path, NULL);
    if (!fmt || fmt->video_codec == AV_CODEC_ID_NONE) {
        log_error("%s: not a movie name: expected .mp4, .mkv, .mov or another video container",
                  path);
        return NULL;
    }
    const AVCodec *codec = pick_encoder(fmt, d->codec, path);
    if (!codec)
        return NULL;
    struct video_writer *v = calloc(1, sizeof(*v));
    if (!v) {
        log_error("%s: out of memory", path);
        return NULL;
    }
    snprintf(v->path, sizeof(v->path), "%s", path);
    /* Written beside its target (through a link; never over a read-only file) and renamed
     * into place at the end; a signal removes it (common/fatal). */
    unsigned mode = 0644;
    if (!file_write_target(path, v->target, sizeof(v->target), &mode)) {
        free(v);
        return NULL;
    }
    snprintf(v->tmp, sizeof(v->tmp), "%s.tmpXXXXXX", v->target);
    int fd = fatal_mkstemp(v->tmp);
    if (fd < 0) {
        log_error("%s: cannot create a temporary file beside it: %s", path, strerror(errno));
        free(v);
        return NULL;
    }
    if (fchmod(fd, (mode_t)mode) != 0)
        log_warn("%s: cannot set the file's permissions: %s", path, strerror(errno));
    close(fd);
    /* 4:2:0 halves both sides: an odd side gets its last row or column once more. */
    v->in_width = d->width;
    v->in_height = d->height;
    v->width = d->width + d->width % 2;
    v->height = d->height + d->height % 2;
    int rc = avformat_alloc_output_context2(&v->oc, fmt, NULL, v->tmp);
    v->enc = avcodec_alloc_context3(codec);
    v->frame = av_frame_alloc();
    v->pkt = av_packet_alloc();
    v->rgb = malloc((size_t)v->width * (size_t)v->height * 3);
    if (rc < 0 || !v->oc || !v->enc || !v->frame || !v->pkt || !v->rgb) {
        log_error("%s: cannot set up the movie: %s", path,
                  rc < 0 ? av_text(rc, err, sizeof(err)) : "out of memory");
        video_abort(v);
        return NULL;
    }
    v->st = avformat_new_stream(v->oc, NULL);
    AVCodecContext *c = v->enc;
    c->width = v->width;
    c->height = v->height;
    c->time_base = (AVRational){1, d->fps};
    c->framerate = (AVRational){d->fps, 1};
    c->gop_size = d->fps;
    c->pix_fmt = AV_PIX_FMT_YUV420P;
    c->color_primaries = AVCOL_PRI_BT709;
    c->color_trc = AVCOL_TRC_IEC61966_2_1; /* the frames are sRGB-encoded, as PNGs are */
    c->colorspace = AVCOL_SPC_BT709;
    c->color_range = AVCOL_RANGE_MPEG;
    if (fmt->flags & AVFMT_GLOBALHEADER)
        c->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    AVDictionary *opts = NULL;
    if (strcmp(codec->name, "libx264") == 0) {
        char crf[16];
        snprintf(crf, sizeof(crf), "%d", d->quality > 0 ? d->quality : 18);
        av_dict_set(&opts, "crf", crf, 0);
        av_dict_set(&opts, "preset", "medium", 0);
    } else if (d->quality > 0) {
        c->flags |= AV_CODEC_FLAG_QSCALE;
        c->global_quality = FF_QP2LAMBDA * d->quality;
    } else if (codec->id == AV_CODEC_ID_MPEG4) {
        c->flags |= AV_CODEC_FLAG_QSCALE;
        c->global_quality = FF_QP2LAMBDA * 2;
    }
    rc = v->st ? avcodec_open2(c, codec, &opts) : AVERROR(ENOMEM);
    av_dict_free(&opts);
    if (rc < 0) {
        log_error("%s: the %s encoder refused %dx%d at %d frames/s: %s", path, codec->name,
                  d->width, d->height, d->fps, av_text(rc, err, sizeof(err)));
        video_abort(v);
        return NULL;
    }
    v->st->time_base = c->time_base;
    v->st->avg_frame_rate = c->framerate;
    rc = avcodec_parameters_from_context(v->st->codecpar, c);
    v->frame->format = c->pix_fmt;
    v->frame->width = c->width;
    v->frame->height = c->height;
    if (rc >= 0)
        rc = av_frame_get_buffer(v->frame, 0);
    if (rc >= 0)
        rc = avio_open(&v->oc->pb, v->tmp, AVIO_FLAG_WRITE);
    if (rc >= 0) {
        rc = avformat_write_header(v->oc, NULL);
        v->header_written = rc >= 0;
    }
    v->sws = sws_getContext(v->width, v->height, AV_PIX_FMT_RGB24, v->width, v->height,
                            AV_PIX_FMT_YUV420P, SWS_BICUBIC | SWS_ACCURATE_RND, NULL, NULL,
                            NULL);
    if (rc >= 0 && v->sws) {
        /* RGB in full range in, BT.709 limited range out. */
        sws_setColorspaceDetails(v->sws, sws_getCoefficients(SWS_CS_ITU709), 1,
                                 sws_getCoefficients(SWS_CS_ITU709), 0, 0, 1 << 16, 1 << 16);
    }
    if (rc < 0 || !v->sws) {
        log_error("%s: cannot start the movie: %s", path,
                  rc < 0 ? av_text(rc, err, sizeof(err)) : "no colour converter");
        video_abort(v);
        return NULL;
    }
    log_info("movie %s: %s, %dx%d at %d frames/s", path, codec->name, v->width, v->height,
             d->fps);
    return v;
}

/* Sends FRAME (NULL: the end) and writes the packets the encoder has. */
static bool encode(struct video_writer *v, AVFrame *frame)
{
    char err[128];
    int rc = avcodec_send_frame(v->enc, frame);
    while (rc >= 0) {
        rc = avcodec_receive_packet(v->enc, v->pkt);
        if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF)
            return true;
        if (rc < 0)
            break;
        av_packet_rescale_ts(v->pkt, v->enc->time_base, v->st->time_base);
        v->pkt->stream_index = v->st->index;
        rc = av_interleaved_write_frame(v->oc, v->pkt);
    }
    log_error("%s: encoding frame %d failed: %s", v->path, v->frames,
              av_text(rc, err, sizeof(err)));
    return false;
}

bool video_add_frame(struct video_writer *v, const struct image *img, float exposure)
{
    if (img->width != v->in_width || img->height != v->in_height) {
        log_error("%s: frame %d is %dx%d, the movie's frames %dx%d", v->path, v->frames,
                  img->width, img->height, v->in_width, v->in_height);
        return false;
    }
    for (int y = 0; y < v->height; y++) {
        int sy = y < v->in_height ? y : v->in_height - 1;
        const float *src = img->rgba + (size_t)(v->in_height - 1 - sy) * v->in_width * 4;
        uint8_t *dst = v->rgb + (size_t)y * v->width * 3;
        for (int x = 0; x < v->width; x++) {
            int sx = x < v->in_width ? x : v->in_width - 1;
            for (int c = 0; c < 3; c++)
                dst[3 * x + c] = image_tonemap(src[4 * sx + c], exposure);
        }
    }
    if (av_frame_make_writable(v->frame) < 0) {
        log_error("%s: out of memory", v->path);
        return false;
    }
    const uint8_t *planes[1] = {v->rgb};
    const int strides[1] = {3 * v->width};
    sws_scale(v->sws, planes, strides, 0, v->height, v->frame->data, v->frame->linesize);
    v->frame->pts = v->frames;
    if (!encode(v, v->frame))
        return false;
    v->frames++;
    return true;
}

int video_frames(const struct video_writer *v)
{
    return v->frames;
}

bool video_close(struct video_writer *v)
{
    if (!v)
        return false;
    char err[128];
    bool ok = encode(v, NULL);
    int rc = ok ? av_write_trailer(v->oc) : 0;
    if (rc < 0)
        log_error("%s: cannot finish the movie: %s", v->path, av_text(rc, err, sizeof(err)));
    ok = ok && rc >= 0;
    if (v->oc->pb && avio_closep(&v->oc->pb) < 0 && ok) {
        log_error("%s: cannot write the movie: %s", v->path, strerror(errno));
        ok = false;
    }
    if (ok && rename(v->tmp, v->target) != 0) {
        log_error("%s: cannot put the movie in place: %s", v->path, strerror(errno));
        ok = false;
    }
    if (!ok)
        unlink(v->tmp);
    else
        log_info("wrote %s (%d frames)", v->path, v->frames);
    fatal_untrack(v->tmp);
    destroy(v);
    return ok;
}

void video_abort(struct video_writer *v)
{
    if (!v)
        return;
    if (v->oc && v->oc->pb)
        avio_closep(&v->oc->pb);
    unlink(v->tmp);
    fatal_untrack(v->tmp);
    destroy(v);
}
