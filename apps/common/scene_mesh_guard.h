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

/* How much of the file's start sr_mesh_guard_header looks at. */
#define SR_MESH_GUARD_HEAD_BYTES 65536u

/* Opens `path` and checks it is a regular file (not a directory, FIFO or
 * device, which assimp would read forever or not at all) of 1 to
 * SR_MESH_MAX_FILE_BYTES bytes; then reads its first bytes into `head`
 * (SR_MESH_GUARD_HEAD_BYTES of room), their number into `*head_len` and the
 * file's size into `*size`. NOT_FOUND, IO or LIMIT, naming `label`. */
sluice_status sr_mesh_guard_file(const char *path, const char *label, unsigned char *head,
                                 size_t *head_len, size_t *size, char *err, size_t err_size);

/* Checks the counts a file's header declares (OFF: vertices and faces; PLY:
 * every element) against what `size` bytes can hold. `head` is the file's
 * first `head_len` bytes. Files in other formats pass. LIMIT, naming
 * `label`, the count and the size. */
sluice_status sr_mesh_guard_header(const unsigned char *head, size_t head_len, size_t size,
                                   const char *label, char *err, size_t err_size);

#endif /* SR_APPS_SCENE_MESH_GUARD_H */
