/* JSON output shared by the renderers' statistics files. */
#ifndef SR_JSON_H
#define SR_JSON_H

#include "sluice/sluice.h"

#include <stdio.h>

/** Writes `s` (NULL: empty) as a JSON string, quotes included: quotes and
 *  backslashes escaped, control characters as \u00XX. */
void sr_json_string(FILE *f, const char *s);

/** Writes the context's kernel profile (sluice_profile_get) as the member
 *  `"kernels": [...]`, one object a kernel with its name, launches, records
 *  in and out and device seconds, each on its own line indented by `indent`
 *  + 2 spaces; an empty list when profiling is off. No trailing comma or
 *  newline. */
void sr_json_kernels(FILE *f, sluice_context *ctx, int indent);

#endif /* SR_JSON_H */
