/* Data files found relative to the running executable (data_path.h). */
#include "data_path.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The way from bindir to datadir, given by the build (meson.build: "../share"
 * for the usual layout, or an absolute datadir). */
#ifndef SR_BIN_TO_DATA
#define SR_BIN_TO_DATA "../share"
#endif

int sr_path_dir(const char *path, char *out, size_t size)
{
    const char *slash = strrchr(path, '/');
    size_t n = !slash ? 1 : slash == path ? 1 : (size_t)(slash - path);
    if (n >= size)
        return -1;
    memcpy(out, slash ? path : ".", n);
    out[n] = '\0';
    return 0;
}

int sr_exe_dir(char *out, size_t size)
{
    if (!out || size < 2)
        return -1;
    /* readlink does not terminate and truncates silently: a result that
     * fills the buffer may have been cut. */
    ssize_t n = readlink("/proc/self/exe", out, size);
    if (n <= 0 || (size_t)n >= size)
        return -1;
    out[n] = 0;
    char *slash = strrchr(out, '/');
    if (!slash)
        return -1;
    if (slash == out)
        slash[1] = 0; /* the executable lies in / */
    else
        *slash = 0;
    return 0;
}

int sr_exe_relative_dir(const char *way, char *out, size_t size)
{
    int n;
    if (way[0] == '/') {
        n = snprintf(out, size, "%s", way);
    } else {
        char exe[4096];
        if (sr_exe_dir(exe, sizeof exe) != 0)
            return -1;
        /* The executable's folder has no symbolic links left (the kernel
         * resolved them), so each leading ".." may simply drop its last
         * component: error messages then show plain paths. */
        while (strncmp(way, "../", 3) == 0 || strcmp(way, "..") == 0) {
            char *slash = strrchr(exe, '/');
            if (!slash || slash == exe)
                break;
            *slash = 0;
            way += way[2] ? 3 : 2;
        }
        n = snprintf(out, size, "%s%s%s", exe, *way ? "/" : "", way);
    }
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

int sr_data_dir(const char *sub, char *out, size_t size)
{
    char data[4096];
    if (sr_exe_relative_dir(SR_BIN_TO_DATA, data, sizeof data) != 0)
        return -1;
    const char *sep = sub && *sub ? "/" : "";
    int n = snprintf(out, size, "%s/sluice%s%s", data, sep, sub ? sub : "");
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

/* Appends `text` to `buf` (NUL-terminated, `size` bytes), cutting it short
 * if it does not fit. */
static void append(char *buf, size_t size, const char *text)
{
    size_t len = strlen(buf);
    if (len + 1 < size)
        snprintf(buf + len, size - len, "%s", text);
}

int sr_find_file(const char *file, const char *const *dirs, size_t n_dirs, char *out,
                 size_t out_size, char *tried, size_t tried_size)
{
    if (tried && tried_size)
        tried[0] = 0;
    if (!file || !out || !out_size)
        return -1;
    for (size_t i = 0; i < n_dirs; ++i) {
        if (!dirs[i] || !dirs[i][0])
            continue;
        char path[4096];
        int n = snprintf(path, sizeof path, "%s/%s", dirs[i], file);
        if (n < 0 || (size_t)n >= sizeof path)
            continue;
        if (tried && tried_size) {
            if (tried[0])
                append(tried, tried_size, ", ");
            append(tried, tried_size, path);
        }
        struct stat st;
        if (stat(path, &st) == 0 && S_ISREG(st.st_mode) && access(path, R_OK) == 0 &&
            (size_t)n < out_size) {
            memcpy(out, path, (size_t)n + 1);
            return 0;
        }
    }
    return -1;
}

int sr_find_data_file(const char *sub, const char *file, int next_to_exe, const char *build_dir,
                      char *out, size_t out_size, char *tried, size_t tried_size)
{
    char exe[4096], data[4096];
    const char *dirs[3] = {NULL, NULL, build_dir};
    if (next_to_exe && sr_exe_dir(exe, sizeof exe) == 0)
        dirs[0] = exe;
    if (sr_data_dir(sub, data, sizeof data) == 0)
        dirs[1] = data;
    return sr_find_file(file, dirs, 3, out, out_size, tried, tried_size);
}
