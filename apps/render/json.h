/* JSON output shared by the renderers' statistics files. */
#ifndef SR_JSON_H
#define SR_JSON_H

#include <stdio.h>

/** Writes `s` (NULL: empty) as a JSON string, quotes included: quotes and
 *  backslashes escaped, control characters as \u00XX. */
void sr_json_string(FILE *f, const char *s);

#endif /* SR_JSON_H */
