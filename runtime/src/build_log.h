/* OpenCL compilers' build logs rewritten into one shape (build_log.c). Pure
 * text processing, no OpenCL: unit-tested on vendors' sample logs
 * (tests/test_build_log.c, tests/data/build_log/). */
#ifndef SLUICE_BUILD_LOG_H
#define SLUICE_BUILD_LOG_H

#include <stdbool.h>
#include <stddef.h>

/* Rewrites a compiler's build log into diagnostic lines of one shape,
 *
 *     FILE:LINE:COL: error: MESSAGE
 *
 * (FILE:LINE: when the compiler gave no column), whichever vendor wrote it:
 * clang's own `FILE:LINE:COL: error: MESSAGE` (NVIDIA, AMD, Intel, Mesa) and
 * PoCL's `error: FILE:LINE:COL: MESSAGE` (with ` <Spelling=...>` after the
 * location of an error inside a macro expansion, which is dropped: the
 * expansion site is the user's line). A file name that is a vendor's
 * placeholder for the program's only source (none at all, `<kernel>`,
 * `<source>`, `<stdin>`, `<string>`, a path ending in `CompileSource`, or a
 * source index such as Intel's `1`) becomes `name`.
 *
 * Errors come first, in the log's order; then, only `with_warnings`, the
 * warnings. Notes and repeated lines are dropped. Errors without a location
 * (`error: Compiler frontend failed`) appear as `name: error: MESSAGE`, and
 * only when the log has no located error. Every line ends in '\n'.
 *
 * `*more` (when not NULL) is set to whether the log holds anything but
 * diagnostics, blank lines and the compilers' closing chatter ("2 errors
 * generated.", PoCL's "Device ... failed to build the program"): source
 * excerpts, carets, "In file included from" - reasons to show the raw log
 * as well.
 *
 * Returns a malloc'd string ("" when the log has no error, nor a warning
 * asked for), or NULL when out of memory. */
char *sl_build_log_digest(const char *log, const char *name, bool with_warnings, bool *more);

/* The log with the locations a compiler gave in its placeholder for the
 * source (`<kernel>:533:2: warning: ...`) mapped through the `#line N
 * "FILE"` directives of `source`, the text that was handed to it, to
 * `FILE:LINE:COL: warning: ...`. Compilers that ignore the directives
 * (NVIDIA's) count lines of the whole text; those that follow them already
 * give the names (PoCL), and their lines pass unchanged, as does every line
 * when `source` has no directive. Returns a malloc'd string, or NULL when
 * out of memory. */
char *sl_build_log_relocate(const char *log, const char *source);

/* Is this clang's count of diagnostics, "2 warnings generated." or "1
 * warning and 1 error generated." (a trailing newline allowed)? PoCL's
 * compiler writes it on stderr, others at the end of their log. */
bool sl_build_log_is_count(const char *line, size_t len);

#endif /* SLUICE_BUILD_LOG_H */
