/*
 * render/video: movies through FFmpeg's libraries (libavformat, libavcodec, libswscale).  The
 * frames are tone-mapped exactly as PNG files are (image_tonemap: sRGB), converted to 4:2:0
 * YUV with the BT.709 matrix in limited range, encoded at a constant frame rate and tagged
 * with those colours (BT.709 primaries and matrix, the sRGB transfer curve, limited range).
 * The container follows the file name (.mp4, .mkv, .mov, ...).  The file is written under a
 * temporary name beside it and renamed into place by video_close, so a failed or abandoned
 * movie never replaces an older one.  No GL.
 */
#ifndef ANVIL_RENDER_VIDEO_H
#define ANVIL_RENDER_VIDEO_H

#include <stdbool.h>

#include "render/image.h"

struct video_desc {
    int width, height;  /* of the frames; an odd side is made even (4:2:0 halves both) by
                           repeating its last row or column */
    int fps;            /* frames per second, constant */
    const char *codec;  /* an FFmpeg encoder name ("libx264", "mpeg4"); NULL: H.264 when this
                           FFmpeg has an encoder for it, else the container's default */
    int quality;        /* 0: the default (x264: CRF 18, visually lossless); else the
                           encoder's constant quality (x264's CRF, 0..51) */
};

struct video_writer;

/* Whether PATH names a movie (an extension FFmpeg knows a video container for). */
bool video_path_supported(const char *path);

/* Whether a movie can be made at PATH with CODEC (NULL: the default): the container known,
 * the encoder there and able to go in it.  False with one message otherwise. */
bool video_check(const char *path, const char *codec);

/* Opens a movie at PATH (written under a temporary name until video_close).  NULL (logged:
 * the path, what FFmpeg said) when the container, the encoder or the file cannot be had. */
struct video_writer *video_open(const char *path, const struct video_desc *d);
/* Adds one frame: IMG (desc's size) tone-mapped with EXPOSURE.  False (logged) on failure. */
bool video_add_frame(struct video_writer *v, const struct image *img, float exposure);
/* Finishes the movie and renames it into place.  False (logged) on failure: then nothing is
 * left at PATH that was not there before.  Frees V either way. */
bool video_close(struct video_writer *v);
/* Drops an unfinished movie (its temporary file goes).  NULL is fine. */
void video_abort(struct video_writer *v);
/* Frames added so far. */
int video_frames(const struct video_writer *v);

/* The encoder names this FFmpeg offers for video, for messages and --help ("libx264 mpeg4
 * ..."); a static string. */
const char *video_encoders(void);

#endif
