/* See app_error.h. */
#include "app_error.h"

#include <stdarg.h>
#include <stdio.h>

void sr_set_error(char *err, size_t err_size, const char *fmt, ...)
{
    if (!err || !err_size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, err_size, fmt, ap);
    va_end(ap);
}
