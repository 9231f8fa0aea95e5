/* Counts the assimp scenes the loader holds, for the harnesses: assimp leaks
 * on some of its own error paths (its PLY parser drops the mesh it was
 * filling when a number does not parse), so LeakSanitizer is told to ignore
 * leaks under assimp's importers (lsan.supp), and that would hide a scene
 * the loader forgot to release. Linked with --wrap for the four functions
 * below (fuzz.sh), these count imports and releases; a harness checks that
 * none is left after each input. */
#include "live_scenes.h"

#include <assimp/cimport.h>
#include <assimp/scene.h>

long fuzz_live_scenes;

const struct aiScene *__real_aiImportFileExWithProperties(const char *path, unsigned flags,
                                                          struct aiFileIO *io,
                                                          const struct aiPropertyStore *props);
const struct aiScene *
__real_aiImportFileFromMemoryWithProperties(const char *data, unsigned size, unsigned flags,
                                            const char *hint, const struct aiPropertyStore *props);
const struct aiScene *__real_aiApplyPostProcessing(const struct aiScene *scene, unsigned flags);
void __real_aiReleaseImport(const struct aiScene *scene);

const struct aiScene *__wrap_aiImportFileExWithProperties(const char *path, unsigned flags,
                                                          struct aiFileIO *io,
                                                          const struct aiPropertyStore *props);
const struct aiScene *
__wrap_aiImportFileFromMemoryWithProperties(const char *data, unsigned size, unsigned flags,
                                            const char *hint, const struct aiPropertyStore *props);
const struct aiScene *__wrap_aiApplyPostProcessing(const struct aiScene *scene, unsigned flags);
void __wrap_aiReleaseImport(const struct aiScene *scene);

const struct aiScene *__wrap_aiImportFileExWithProperties(const char *path, unsigned flags,
                                                          struct aiFileIO *io,
                                                          const struct aiPropertyStore *props)
{
    const struct aiScene *s = __real_aiImportFileExWithProperties(path, flags, io, props);
    fuzz_live_scenes += s != NULL;
    return s;
}

const struct aiScene *
__wrap_aiImportFileFromMemoryWithProperties(const char *data, unsigned size, unsigned flags,
                                            const char *hint, const struct aiPropertyStore *props)
{
    const struct aiScene *s =
        __real_aiImportFileFromMemoryWithProperties(data, size, flags, hint, props);
    fuzz_live_scenes += s != NULL;
    return s;
}

const struct aiScene *__wrap_aiApplyPostProcessing(const struct aiScene *scene, unsigned flags)
{
    /* on failure assimp releases the scene itself */
    const struct aiScene *s = __real_aiApplyPostProcessing(scene, flags);
    fuzz_live_scenes -= scene != NULL && s == NULL;
    return s;
}

void __wrap_aiReleaseImport(const struct aiScene *scene)
{
    fuzz_live_scenes -= scene != NULL;
    __real_aiReleaseImport(scene);
}
