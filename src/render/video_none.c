/* render/video without FFmpeg (cmake -DANVIL_VIDEO=OFF): a movie's name is still known for
 * one, so that asking for it gets one clear message instead of a PNG of that name. */
#include "render/video.h"

#include <strings.h>
#include <string.h>

#include "common/log.h"

bool video_path_supported(const char *path)
{
    static const char *const movies[] = {".mp4", ".mkv", ".mov",  ".webm", ".avi",  ".m4v",
                                         ".ogv", ".mpg", ".mpeg", ".ts",   ".m2ts", ".flv",
                                         ".wmv", ".asf", ".3gp",  ".mxf",  ".nut",  ".y4m"};
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return false;
    for (size_t i = 0; i < sizeof(movies) / sizeof(movies[0]); i++)
        if (strcasecmp(dot, movies[i]) == 0)
            return true;
    return false;
}

static void refuse(const char *path)
{
    log_error("%s: this anvil was built without FFmpeg (cmake -DANVIL_VIDEO=OFF) and writes no "
              "movies: write the frames as PNG files (-o out/frame-%%05d.png) and make the movie "
              "from them elsewhere",
              path);
}

bool video_check(const char *path, const char *codec)
{
    (void)codec;
    refuse(path);
    return false;
}

struct video_writer *video_open(const char *path, const struct video_desc *d)
{
    (void)d;
    refuse(path);
    return NULL;
}

bool video_add_frame(struct video_writer *v, const struct image *img, float exposure)
{
    (void)v;
    (void)img;
    (void)exposure;
    return false;
}

bool video_close(struct video_writer *v)
{
    (void)v;
    return false;
}

void video_abort(struct video_writer *v)
{
    (void)v;
}

int video_frames(const struct video_writer *v)
{
    (void)v;
    return 0;
}

const char *video_encoders(void)
{
    return "none (built without FFmpeg)";
}
