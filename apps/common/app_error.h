/* Error text for the apps' libraries (images, scenes): functions return a
 * sluice_status and describe the failure in a caller's buffer. */
#ifndef SLUICE_APP_ERROR_H
#define SLUICE_APP_ERROR_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Formats a message into `err` (at most `err_size` bytes, NUL-terminated).
 *  Does nothing when `err` is NULL or `err_size` is 0, so callers may pass
 *  no buffer at all. */
void sluice_set_error(char *err, size_t err_size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#ifdef __cplusplus
}
#endif

#endif /* SLUICE_APP_ERROR_H */
