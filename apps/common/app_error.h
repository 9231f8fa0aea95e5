/* Error text for the apps' libraries (images, scenes): functions return a
 * sluice_status and describe the failure in a caller's buffer. */
#ifndef SR_APP_ERROR_H
#define SR_APP_ERROR_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Formats a message into `err` (at most `err_size` bytes, NUL-terminated).
 *  Does nothing when `err` is NULL or `err_size` is 0, so callers may pass
 *  no buffer at all. */
void sr_set_error(char *err, size_t err_size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#ifdef __cplusplus
}
#endif

#endif /* SR_APP_ERROR_H */
