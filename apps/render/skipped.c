/* See skipped.h. */
#include "skipped.h"

#include <stdio.h>
#include <string.h>

void sr_skipped_add(char *list, size_t size, int cond, const char *what)
{
    if (!cond || !list || !size || !what)
        return;
    size_t used = strnlen(list, size);
    if (used >= size)
        return;
    const char *sep = used ? "; " : "";
    if (used + strlen(sep) + strlen(what) >= size)
        return;
    snprintf(list + used, size - used, "%s%s", sep, what);
}
