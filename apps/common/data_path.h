/* Finding the data files that the apps install (the examples' kernels, the
 * scenes) at run time. An installed program looks for them relative to its
 * own location, not at the prefix it was configured with, so that an install
 * staged with `meson install --destdir` or moved to another folder finds its
 * own files; see docs/install.md. */
#ifndef SR_DATA_PATH_H
#define SR_DATA_PATH_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Writes the folder of `path` into `out`: what comes before its last '/'
 *  ("/" for a file at the root, "." for a bare name). Returns 0, or -1 when
 *  it does not fit in `size` bytes. */
int sr_path_dir(const char *path, char *out, size_t size);

/** Writes the folder of the running executable (from /proc/self/exe, with
 *  symbolic links resolved) into `out`. Returns 0, or -1 when it cannot be
 *  read (not Linux, no /proc) or does not fit in `size` bytes. */
int sr_exe_dir(char *out, size_t size);

/** Writes the folder `way` leads to from the running executable's folder
 *  into `out`: `way` itself when absolute, else the executable's folder
 *  followed by `way`, its leading ".." components taken off that folder.
 *  Returns 0, or -1 as sr_exe_dir() does. Does not check that it exists. */
int sr_exe_relative_dir(const char *way, char *out, size_t size);

/** Writes the installed data folder `<datadir>/sluice/<sub>` as seen from
 *  the running executable (`<exe dir>/../share/sluice/<sub>` for the usual
 *  bindir and datadir; an absolute path when the build was configured with
 *  an absolute datadir outside the prefix) into `out`. `sub` may be NULL or
 *  "". Returns 0, or -1 as sr_exe_dir() does. Does not check that it exists. */
int sr_data_dir(const char *sub, char *out, size_t size);

/** Looks for `file` in each of the `n_dirs` folders `dirs`, in order (NULL
 *  or "" entries are skipped), and writes the first path that names a
 *  readable regular file into `out`; returns 0. Otherwise returns -1 and
 *  writes every path it tried, separated by ", ", into `tried` (which may be
 *  NULL), for the caller's error message. */
int sr_find_file(const char *file, const char *const *dirs, size_t n_dirs, char *out,
                 size_t out_size, char *tried, size_t tried_size);

/** Finds the data file `file` of kind `sub` ("examples", "scenes"): next to
 *  the running executable when `next_to_exe`, else in the installed data
 *  folder (sr_data_dir(sub)), else in `build_dir` (the source tree's folder,
 *  recorded at build time; may be NULL). Returns 0 with the path in `out`, or
 *  -1 with the paths tried in `tried` as sr_find_file() does. */
int sr_find_data_file(const char *sub, const char *file, int next_to_exe, const char *build_dir,
                      char *out, size_t out_size, char *tried, size_t tried_size);

#ifdef __cplusplus
}
#endif

#endif /* SR_DATA_PATH_H */
