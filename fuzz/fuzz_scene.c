/* libFuzzer target: the scene parser (scene_parse_string_all) on arbitrary bytes,
 * then the render-scene factories (render_scene_create, no rendering) on what
 * parses. Neither may crash, leak, hang, read out of bounds or hit undefined
 * behaviour; errors are the expected outcome for most inputs. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "render/render_scene.h"
#include "scene/scene_desc.h"

/* The scene's name: relative Include, plymesh and VDB paths resolve against its
 * directory, which does not exist, so inputs cannot reach files by accident. */
#define FUZZ_SCENE_NAME "/nonexistent-haze-fuzz/fuzz.pbrt"

static bool contains(const char *text, const char *needle)
{
    return strstr(text, needle) != NULL;
}

/* The Film's pixel count, read without marking parameters used (the factories
 * must see them as the scene gave them); pbrt-v4's default is 1280x720. */
static double film_pixels(const scene_desc *sd)
{
    double res[2] = {1280, 720};
    const char *names[2] = {"xresolution", "yresolution"};
    const param_list *pl = &sd->film.params;
    for (size_t i = 0; i < pl->count; i++)
        for (int k = 0; k < 2; k++)
            if (pl->items[i].type == PARAM_INTEGER && pl->items[i].count >= 1 &&
                strcmp(pl->items[i].name, names[k]) == 0)
                res[k] = pl->items[i].nums[0];
    return res[0] * res[1];
}

/* The film allocates all its pixels up front; haze accepts films up to 64 GiB,
 * which a few digits of xresolution reach. Larger films are not built (they
 * exceed libFuzzer's 2 GB malloc limit without being a bug). */
#define FUZZ_MAX_FILM_PIXELS (4.0 * 1024 * 1024)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* scene_parse_string reads a C string: an embedded NUL ends the text. */
    char *text = malloc(size + 1);
    if (!text)
        return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    /* Absolute paths may still name devices that never end (/dev/zero) or
     * block (/dev/stdin): those are not parser bugs, skip them. */
    if (contains(text, "/dev") || contains(text, "/proc") || contains(text, "/sys")) {
        free(text);
        return 0;
    }
    scene_desc sd;
    hz_error err;
    hz_errors errs = {0};
    if (scene_parse_string_all(text, FUZZ_SCENE_NAME, &sd, &errs, &err) == HZ_OK) {
        /* The factories interpret every parameter and read the files the scene
         * names (plymesh, VDB); relative names resolve inside the nonexistent
         * directory, absolute ones could reach anything, so scenes with a
         * string starting with '/' are not built. A scene with parse errors
         * is built too (render_scene_check), as haze render does to report
         * its other problems. */
        if (!contains(text, "\"/") && film_pixels(&sd) <= FUZZ_MAX_FILM_PIXELS) {
            render_options opt = {.seed = 0, .spp = 1, .output = NULL};
            render_scene *rs = NULL;
            if (errs.count || errs.dropped)
                render_scene_check(&sd, &opt, &errs, &err);
            else if (render_scene_create(&sd, &opt, NULL, &rs, &err) == HZ_OK)
                render_scene_destroy(rs);
        }
        hz_errors_finish(&errs, NULL, 0, NULL);
        scene_desc_free(&sd);
    }
    free(text);
    return 0;
}
