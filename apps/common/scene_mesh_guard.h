/* Checks made before a mesh file reaches assimp (scene_mesh.c). assimp
 * trusts the element counts a file declares and allocates for them before
 * reading the elements: the 309-byte invalid/OutOfMemory.off of assimp's test
 * models declares 353535235358 vertices and takes every byte of memory and
 * over 20 s before assimp's own assertion aborts the process. Bounding the
 * file's size, and each declared count by what that size can hold, bounds
 * what assimp allocates and how long it takes. The limits are in scene.h
 * (SR_MESH_MAX_FILE_BYTES) and docs/scenes.md. */
#ifndef SR_APPS_SCENE_MESH_GUARD_H
#define SR_APPS_SCENE_MESH_GUARD_H

#include "sluice/sluice.h"

#include <stddef.h>

/* How much of the file's start the header checks look at: a PLY header
 * must end within it. */
#define SR_MESH_GUARD_HEAD_BYTES 65536u

/* Checks the file at `path` before assimp reads it: a regular file (not a
 * directory, FIFO or device, which assimp would read forever or not at
 * all) of 1 to SR_MESH_MAX_FILE_BYTES bytes; an OFF or PLY header that
 * declares no more elements than the file's size holds; a PLY header that
 * ends and names known types; binary PLY data that holds what its header
 * says; no NUL byte in an OBJ file (by its extension). NOT_FOUND, IO or
 * LIMIT, naming `label`. */
sluice_status sr_mesh_guard_file(const char *path, const char *label, char *err, size_t err_size);

/* The same checks for `size` bytes at `data` in the format `hint` (an
 * extension, may be NULL). */
sluice_status sr_mesh_guard_memory(const void *data, size_t size, const char *hint,
                                   const char *label, char *err, size_t err_size);

#endif /* SR_APPS_SCENE_MESH_GUARD_H */
