/* libFuzzer harness for the mesh loader (sr_scene_builder_add_mesh_memory,
 * the code behind sr_scene_builder_add_mesh_file): the first byte picks the
 * format hint assimp gets, the rest is the file. Each input must end in a
 * scene or a clean error; crashes, sanitizer reports, leaks, timeouts and
 * out-of-memory are the findings. Built by `make fuzz` (tests/fuzz/README.md). */
#include "live_scenes.h"
#include "scene.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* The formats docs/scenes.md names, then "" (assimp guesses from content,
 * which reaches its other loaders too). */
static const char *const HINTS[] = {"obj", "ply", "off", "stl", "gltf", "glb", ""};
#define HINT_COUNT (sizeof HINTS / sizeof HINTS[0])

/* Bounds the work one input may ask for (see sr_scene_load_options). */
#define FUZZ_MAX_TRIANGLES (1u << 18)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    const char *hint = HINTS[data[0] % HINT_COUNT];
    sr_scene_builder *b = NULL;
    if (sr_scene_builder_create("fuzz", &b) != SLUICE_OK)
        return 0;
    sr_scene_builder_set_max_triangles(b, FUZZ_MAX_TRIANGLES);
    char err[1024];
    err[0] = '\0';
    sluice_status st = sr_scene_builder_add_mesh_memory(b, data + 1, size - 1, hint, NULL, NULL,
                                                        "fuzz", err, sizeof err);
    if (st == SLUICE_OK) {
        sr_scene *s = NULL;
        if (sr_scene_builder_finish(b, SR_SCENE_DEFAULT_LIGHT, &s, err, sizeof err) == SLUICE_OK)
            sr_scene_destroy(s);
    } else if (strlen(err) == 0 || strncmp(err, "fuzz", 4) != 0) {
        /* every failure must say what failed, naming the input */
        __builtin_trap();
    }
    sr_scene_builder_destroy(b);
    if (fuzz_live_scenes != 0)
        __builtin_trap(); /* an assimp scene was not released */
    return 0;
}
