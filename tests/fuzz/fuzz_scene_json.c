/* libFuzzer harness for the JSON scene loader (sr_scene_load_json): each
 * input is written to scene.json in a private directory whose meshes/ links
 * to tests/fuzz/seeds/mesh (tiny files in each format docs/scenes.md names),
 * so the seeds' mesh references resolve and the JSON-to-mesh path is fuzzed
 * too. Each input must end in a scene or
 * a clean error naming the file; crashes, sanitizer reports, leaks, timeouts
 * and out-of-memory are the findings. Built by `make fuzz`
 * (tests/fuzz/README.md); SCENE_SOURCE_ROOT is the repository. */
#define _POSIX_C_SOURCE 200809L
#include "live_scenes.h"
#include "scene.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Bounds the work one input may ask for (see sr_scene_load_options). */
#define FUZZ_MAX_TRIANGLES (1u << 18)

static char scene_path[512];

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    const char *tmp = getenv("TMPDIR");
    char dir[400];
    snprintf(dir, sizeof dir, "%s/sluice-fuzz-json-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        exit(1);
    }
    char link[480];
    snprintf(link, sizeof link, "%s/meshes", dir);
    if (symlink(SCENE_SOURCE_ROOT "/tests/fuzz/seeds/mesh", link) != 0) {
        perror("symlink");
        exit(1);
    }
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    FILE *f = fopen(scene_path, "wb");
    if (!f)
        return 0;
    size_t n = fwrite(data, 1, size, f);
    fclose(f);
    if (n != size)
        return 0;
    sr_scene_load_options o;
    memset(&o, 0, sizeof o);
    o.flags = SR_SCENE_ALLOW_NO_LIGHT;
    o.max_triangles = FUZZ_MAX_TRIANGLES;
    sr_scene *s = NULL;
    char err[1024];
    err[0] = '\0';
    if (sr_scene_load_json(scene_path, &o, &s, err, sizeof err) == SLUICE_OK) {
        sr_scene_destroy(s);
    } else if (strncmp(err, scene_path, strlen(scene_path)) != 0) {
        /* every failure must name the file */
        __builtin_trap();
    }
    if (fuzz_live_scenes != 0)
        __builtin_trap(); /* an assimp scene was not released */
    return 0;
}
