/* Loading the image I/O module (libsluice-image-oiio.so, image_io.cpp) on the
 * first image read or write, and the sr_image_io_* functions of image.h that
 * call into it. Why a module at all: image.h, "The image I/O module". */
#define _GNU_SOURCE /* dlopen's RTLD_* on older C libraries */
#include "image.h"
#include "app_error.h"
#include "data_path.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Given by the build (apps/common/meson.build): the module's file name, the
 * folder it is installed in as seen from bindir (relative, or absolute for
 * an absolute libdir), the folder the build puts it in and the build's top
 * folder. */
#ifndef SR_IMAGE_MODULE_NAME
#define SR_IMAGE_MODULE_NAME "libsluice-image-oiio.so"
#endif
#ifndef SR_BIN_TO_IMAGE_MODULE
#define SR_BIN_TO_IMAGE_MODULE "../lib/sluice"
#endif
#ifndef SR_IMAGE_MODULE_BUILD_DIR
#define SR_IMAGE_MODULE_BUILD_DIR ""
#endif
#ifndef SR_IMAGE_MODULE_BUILD_ROOT
#define SR_IMAGE_MODULE_BUILD_ROOT ""
#endif

/* The module is loaded once per process and never unloaded (OpenImageIO
 * keeps threads and caches of its own), so this is the one piece of
 * process-wide state in the apps' libraries; pthread_once makes the first
 * load safe from any thread. The message of a failed load is kept for every
 * later call. */
static pthread_once_t module_once = PTHREAD_ONCE_INIT;
static const sr_image_io_module *module;
static char module_error[1536];

/* Is the running executable inside the build tree? (Only then may it load
 * the build's module: an installed program must load its own.) */
static int exe_in_build_tree(const char *exe)
{
    char root[4096];
    if (!SR_IMAGE_MODULE_BUILD_ROOT[0] || !realpath(SR_IMAGE_MODULE_BUILD_ROOT, root))
        return 0;
    size_t n = strlen(root);
    return strncmp(exe, root, n) == 0 && (exe[n] == '/' || exe[n] == 0);
}

/* Where the module may be: SLUICE_IMAGE_MODULE (a file, for a module kept
 * elsewhere and for tests), else the installed folder relative to the
 * running executable (so that a moved install finds its own), else, for a
 * program in the build tree, the build's folder. */
static void module_load(void)
{
    char path[4096], tried[1024] = "";
    const char *env = getenv("SLUICE_IMAGE_MODULE");
    if (env && *env) {
        snprintf(path, sizeof path, "%s", env);
    } else {
        char exe[4096], installed[4096];
        const char *dirs[2] = {NULL, NULL};
        if (sr_exe_relative_dir(SR_BIN_TO_IMAGE_MODULE, installed, sizeof installed) == 0)
            dirs[0] = installed;
        if (sr_exe_dir(exe, sizeof exe) == 0 && exe_in_build_tree(exe))
            dirs[1] = SR_IMAGE_MODULE_BUILD_DIR;
        if (sr_find_file(SR_IMAGE_MODULE_NAME, dirs, 2, path, sizeof path, tried, sizeof tried) !=
            0) {
            sr_set_error(module_error, sizeof module_error,
                         "the image module %s (OpenImageIO) is not installed; looked for %s",
                         SR_IMAGE_MODULE_NAME, tried[0] ? tried : "it nowhere");
            return;
        }
    }
    /* RTLD_LOCAL: OpenImageIO's libraries stay out of the global scope that
     * the kernel libraries PoCL loads are linked against. */
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        const char *why = dlerror();
        sr_set_error(module_error, sizeof module_error, "cannot load the image module %s%s: %s",
                     path, env && *env ? " (SLUICE_IMAGE_MODULE)" : "",
                     why ? why : "unknown error");
        return;
    }
    const sr_image_io_module *(*get)(void) = NULL;
    /* POSIX's way to turn dlsym's object pointer into a function pointer. */
    *(void **)&get = dlsym(h, SR_IMAGE_IO_MODULE_SYMBOL);
    const sr_image_io_module *m = get ? get() : NULL;
    if (!m) {
        sr_set_error(module_error, sizeof module_error,
                     "%s is not Sluice's image module (it has no " SR_IMAGE_IO_MODULE_SYMBOL ")",
                     path);
        dlclose(h);
        return;
    }
    if (m->abi != SR_IMAGE_IO_ABI) {
        sr_set_error(module_error, sizeof module_error,
                     "the image module %s is of another Sluice (interface %u, this program's %u): "
                     "reinstall Sluice",
                     path, m->abi, SR_IMAGE_IO_ABI);
        dlclose(h);
        return;
    }
    module = m;
}

/* The loaded module, or NULL with the reason in `err`. */
static const sr_image_io_module *module_get(char *err, size_t err_size)
{
    if (pthread_once(&module_once, module_load) != 0) {
        sr_set_error(err, err_size, "cannot load the image module (pthread_once failed)");
        return NULL;
    }
    if (!module)
        sr_set_error(err, err_size, "%s", module_error);
    return module;
}

sluice_status sr_image_io_load(char *err, size_t err_size)
{
    return module_get(err, err_size) ? SLUICE_OK : SLUICE_ERROR_IO;
}

sluice_status sr_image_io_open(const char *path, sr_image_io_reader **out, sr_image_io_info *info,
                               char *err, size_t err_size)
{
    if (out)
        *out = NULL;
    const sr_image_io_module *m = module_get(err, err_size);
    return m ? m->open(path, out, info, err, err_size) : SLUICE_ERROR_IO;
}

sluice_status sr_image_io_read(sr_image_io_reader *r, int chbegin, int chend, float *pixels,
                               char *err, size_t err_size)
{
    const sr_image_io_module *m = module_get(err, err_size);
    return m ? m->read(r, chbegin, chend, pixels, err, err_size) : SLUICE_ERROR_IO;
}

void sr_image_io_close(sr_image_io_reader *r)
{
    /* A reader exists only if the module was loaded. */
    if (r)
        module->close(r);
}

sluice_status sr_image_io_write(const char *path, unsigned width, unsigned height,
                                unsigned channels, sr_image_io_type type, const void *pixels,
                                char *err, size_t err_size)
{
    const sr_image_io_module *m = module_get(err, err_size);
    return m ? m->write(path, width, height, channels, type, pixels, err, err_size)
             : SLUICE_ERROR_IO;
}
