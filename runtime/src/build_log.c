/* Vendors' build logs rewritten into one shape; see build_log.h. */
#include "build_log.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum severity { SEV_NONE, SEV_ERROR, SEV_WARNING, SEV_NOTE } severity;

/* One diagnostic line, its parts pointing into the log. */
typedef struct diag {
    severity sev;
    bool located;
    const char *file;
    size_t file_len;
    unsigned long line, col; /* col 0: none given */
    const char *msg;
    size_t msg_len;
} diag;

static bool starts_with(const char *s, size_t len, const char *prefix)
{
    size_t pl = strlen(prefix);
    return len >= pl && memcmp(s, prefix, pl) == 0;
}

/* A severity word and ": " at the start of s; *used is their length. */
static severity parse_severity(const char *s, size_t len, size_t *used)
{
    static const struct {
        const char *word;
        severity sev;
    } words[] = {{"fatal error: ", SEV_ERROR},
                 {"error: ", SEV_ERROR},
                 {"warning: ", SEV_WARNING},
                 {"note: ", SEV_NOTE},
                 {"remark: ", SEV_NOTE}};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; ++i)
        if (starts_with(s, len, words[i].word)) {
            *used = strlen(words[i].word);
            return words[i].sev;
        }
    return SEV_NONE;
}

/* Reads decimal digits at s[*i]; false when there are none. */
static bool parse_number(const char *s, size_t len, size_t *i, unsigned long *out)
{
    size_t j = *i;
    unsigned long v = 0;
    while (j < len && isdigit((unsigned char)s[j]) && v < 100000000ul)
        v = v * 10 + (unsigned long)(s[j++] - '0');
    if (j == *i)
        return false;
    *i = j;
    *out = v;
    return true;
}

/* A location `FILE:LINE[:COL][ <Spelling=...>]: ` at the start of s. The
 * file name may be empty (older NVIDIA drivers) or hold colons (a Windows
 * drive): the first colon followed by a number that completes the pattern
 * ends it. */
static bool parse_location(const char *s, size_t len, diag *d, size_t *used)
{
    /* Source excerpts that some compilers print under a diagnostic are
     * indented, or may hold quotes: neither starts a location. */
    if (len == 0 || s[0] == ' ' || s[0] == '\t')
        return false;
    for (size_t p = 0; p + 1 < len && s[p] != '"'; ++p) {
        if (s[p] != ':' || !isdigit((unsigned char)s[p + 1]))
            continue;
        size_t q = p + 1;
        unsigned long line = 0, col = 0;
        parse_number(s, len, &q, &line);
        if (q + 1 < len && s[q] == ':' && isdigit((unsigned char)s[q + 1])) {
            ++q;
            parse_number(s, len, &q, &col);
        }
        if (starts_with(s + q, len - q, " <Spelling=")) {
            const char *end = memchr(s + q, '>', len - q);
            if (!end)
                continue;
            q = (size_t)(end - s) + 1;
        }
        if (!starts_with(s + q, len - q, ": "))
            continue;
        d->located = true;
        d->file = s;
        d->file_len = p;
        d->line = line;
        d->col = col;
        *used = q + 2;
        return true;
    }
    return false;
}

/* Parses one line of the log (without its newline) as a diagnostic: clang's
 * `LOC: SEVERITY: MESSAGE`, PoCL's `SEVERITY: LOC: MESSAGE`, or a bare
 * `SEVERITY: MESSAGE`. */
static bool parse_diag(const char *s, size_t len, diag *d)
{
    memset(d, 0, sizeof *d);
    size_t used = 0, sev_used = 0;
    if (parse_location(s, len, d, &used) &&
        (d->sev = parse_severity(s + used, len - used, &sev_used)) != SEV_NONE) {
        used += sev_used;
    } else {
        memset(d, 0, sizeof *d);
        used = 0;
        d->sev = parse_severity(s, len, &used);
        if (d->sev == SEV_NONE)
            return false;
        size_t loc_used;
        if (parse_location(s + used, len - used, d, &loc_used))
            used += loc_used;
    }
    d->msg = s + used;
    d->msg_len = len - used;
    return true;
}

/* Is this file name a vendor's stand-in for the program's one source? */
static bool is_placeholder(const char *f, size_t len)
{
    static const char *const names[] = {"<kernel>", "<source>", "<stdin>", "<string>"};
    static const char amd[] = "CompileSource";
    if (len == 0)
        return true;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        if (len == strlen(names[i]) && memcmp(f, names[i], len) == 0)
            return true;
    if (len >= sizeof amd - 1 && memcmp(f + len - (sizeof amd - 1), amd, sizeof amd - 1) == 0)
        return true;
    size_t digits = 0;
    while (digits < len && isdigit((unsigned char)f[digits]))
        ++digits;
    return digits == len;
}

/* Does s[0..len) contain `word`? (s need not end there.) */
static bool contains(const char *s, size_t len, const char *word)
{
    size_t wl = strlen(word);
    for (size_t i = 0; i + wl <= len; ++i)
        if (memcmp(s + i, word, wl) == 0)
            return true;
    return false;
}

bool sl_build_log_is_count(const char *line, size_t len)
{
    static const char tail[] = " generated.";
    const size_t tl = sizeof tail - 1;
    while (len && (line[len - 1] == '\n' || line[len - 1] == '\r'))
        --len;
    return len > tl && isdigit((unsigned char)line[0]) && memcmp(line + len - tl, tail, tl) == 0 &&
           (contains(line, len, " warning") || contains(line, len, " error"));
}

/* The compilers' closing lines, which say nothing the diagnostics do not. */
static bool is_chatter(const char *s, size_t len)
{
    if (sl_build_log_is_count(s, len))
        return true;
    if (starts_with(s, len, "Device ")) {
        static const char tail[] = "failed to build the program";
        return len >= sizeof tail - 1 &&
               memcmp(s + len - (sizeof tail - 1), tail, sizeof tail - 1) == 0;
    }
    return starts_with(s, len, "Error: Failed to compile") ||
           starts_with(s, len, "Compilation started") ||
           starts_with(s, len, "Compilation failed") || starts_with(s, len, "Compilation done");
}

/* A growing output string. */
typedef struct text {
    char *buf;
    size_t len, cap;
    bool failed;
} text;

static void text_add(text *t, const char *s, size_t n)
{
    if (t->failed)
        return;
    if (t->len + n + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 256;
        while (t->len + n + 1 > cap)
            cap *= 2;
        char *b = realloc(t->buf, cap);
        if (!b) {
            t->failed = true;
            return;
        }
        t->buf = b;
        t->cap = cap;
    }
    memcpy(t->buf + t->len, s, n);
    t->len += n;
    t->buf[t->len] = 0;
}

/* Does the output already hold this exact line (with its newline)? */
static bool text_has_line(const text *t, const char *line, size_t n)
{
    for (size_t at = 0; t->buf && at + n <= t->len;) {
        if (memcmp(t->buf + at, line, n) == 0)
            return true;
        const char *nl = memchr(t->buf + at, '\n', t->len - at);
        if (!nl)
            break;
        at = (size_t)(nl - t->buf) + 1;
    }
    return false;
}

/* A `#line N "FILE"` directive of the source handed to the compiler: the
 * source's line `at` holds it, so its line at + 1 is FILE's line N. */
typedef struct line_mark {
    unsigned long at, line;
    const char *file;
    size_t file_len;
} line_mark;

/* The #line directives of `source` (NULL when there are none, or on a
 * failed allocation: locations are then left as the compiler gave them). */
static line_mark *find_line_marks(const char *source, size_t *count)
{
    *count = 0;
    line_mark *marks = NULL;
    size_t cap = 0;
    unsigned long at = 1;
    for (const char *s = source; s && *s; ++at) {
        const char *nl = strchr(s, '\n');
        size_t len = nl ? (size_t)(nl - s) : strlen(s), i = 0;
        unsigned long n;
        if (starts_with(s, len, "#line ") && (i = 6, parse_number(s, len, &i, &n)) && i + 2 < len &&
            s[i] == ' ' && s[i + 1] == '"') {
            const char *f = s + i + 2, *q = memchr(f, '"', len - i - 2);
            if (q) {
                if (*count == cap) {
                    cap = cap ? 2 * cap : 4;
                    line_mark *m = realloc(marks, cap * sizeof *m);
                    if (!m) {
                        free(marks);
                        *count = 0;
                        return NULL;
                    }
                    marks = m;
                }
                marks[(*count)++] = (line_mark){at, n, f, (size_t)(q - f)};
            }
        }
        s += len + (nl ? 1 : 0);
    }
    return marks;
}

/* Appends d in the common shape, unless that line is already there. */
static void add_diag(text *t, const diag *d, const char *name)
{
    const char *file = d->file;
    size_t file_len = d->file_len;
    if (!d->located || is_placeholder(file, file_len)) {
        file = name;
        file_len = strlen(name);
    }
    char where[64];
    if (!d->located)
        where[0] = 0;
    else if (d->col)
        snprintf(where, sizeof where, ":%lu:%lu", d->line, d->col);
    else
        snprintf(where, sizeof where, ":%lu", d->line);
    const char *sev = d->sev == SEV_ERROR ? "error" : "warning";
    size_t n = file_len + strlen(where) + strlen(sev) + d->msg_len + 6;
    char *line = malloc(n);
    if (!line) {
        t->failed = true;
        return;
    }
    int len = snprintf(line, n, "%.*s%s: %s: %.*s\n", (int)file_len, file, where, sev,
                       (int)d->msg_len, d->msg);
    if (len > 0 && !text_has_line(t, line, (size_t)len))
        text_add(t, line, (size_t)len);
    free(line);
}

char *sl_build_log_digest(const char *log, const char *name, bool with_warnings, bool *more)
{
    if (more)
        *more = false;
    if (!log)
        log = "";
    if (!name)
        name = "<string>";
    /* Three passes over the log: located errors, then (only when there are
     * none) unlocated ones, then warnings. */
    text out = {NULL, 0, 0, false};
    text_add(&out, "", 0);
    for (int pass = 0; pass < 3; ++pass) {
        if (pass == 1 && out.len > 0)
            continue;
        if (pass == 2 && !with_warnings)
            break;
        for (const char *s = log; *s;) {
            const char *nl = strchr(s, '\n');
            size_t len = nl ? (size_t)(nl - s) : strlen(s);
            size_t trimmed = len;
            while (trimmed && (s[trimmed - 1] == '\r' || s[trimmed - 1] == ' '))
                --trimmed;
            diag d;
            if (parse_diag(s, trimmed, &d)) {
                if ((pass == 0 && d.sev == SEV_ERROR && d.located) ||
                    (pass == 1 && d.sev == SEV_ERROR && !d.located) ||
                    (pass == 2 && d.sev == SEV_WARNING))
                    add_diag(&out, &d, name);
            } else if (pass == 0 && more && trimmed && !is_chatter(s, trimmed)) {
                *more = true;
            }
            s += len + (nl ? 1 : 0);
        }
    }
    if (out.failed) {
        free(out.buf);
        return NULL;
    }
    return out.buf;
}

char *sl_build_log_relocate(const char *log, const char *source)
{
    size_t nmarks;
    line_mark *marks = find_line_marks(source, &nmarks);
    text out = {NULL, 0, 0, false};
    text_add(&out, "", 0);
    for (const char *s = log ? log : ""; *s;) {
        const char *nl = strchr(s, '\n');
        size_t len = nl ? (size_t)(nl - s) : strlen(s), used = 0, k = nmarks;
        diag d;
        memset(&d, 0, sizeof d);
        bool loc = parse_location(s, len, &d, &used) && is_placeholder(d.file, d.file_len);
        while (loc && k > 0 && marks[k - 1].at >= d.line)
            --k;
        if (loc && k > 0) {
            /* The directive on line `at` makes line at + 1 its file's line N. */
            char where[48];
            unsigned long line = marks[k - 1].line + (d.line - marks[k - 1].at - 1);
            if (d.col)
                snprintf(where, sizeof where, ":%lu:%lu", line, d.col);
            else
                snprintf(where, sizeof where, ":%lu", line);
            text_add(&out, marks[k - 1].file, marks[k - 1].file_len);
            text_add(&out, where, strlen(where));
            text_add(&out, s + used - 2, len - (used - 2));
        } else {
            text_add(&out, s, len);
        }
        if (nl)
            text_add(&out, "\n", 1);
        s += len + (nl ? 1 : 0);
    }
    free(marks);
    if (out.failed) {
        free(out.buf);
        return NULL;
    }
    return out.buf;
}
