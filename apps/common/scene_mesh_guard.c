/* See scene_mesh_guard.h. */
#include "scene_mesh_guard.h"
#include "app_error.h"
#include "scene.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

sluice_status sr_mesh_guard_file(const char *path, const char *label, unsigned char *head,
                                 size_t *head_len, size_t *size, char *err, size_t err_size)
{
    /* open first, then fstat: no window in which the path could change */
    FILE *f = fopen(path, "rb");
    if (!f) {
        int e = errno;
        sr_set_error(err, err_size, "%s: cannot open: %s", label,
                     e == ENOENT ? "no such file" : strerror(e));
        return e == ENOENT ? SLUICE_ERROR_NOT_FOUND : SLUICE_ERROR_IO;
    }
    struct stat s;
    sluice_status st = SLUICE_OK;
    if (fstat(fileno(f), &s) != 0) {
        sr_set_error(err, err_size, "%s: cannot open: %s", label, strerror(errno));
        st = SLUICE_ERROR_IO;
    } else if (!S_ISREG(s.st_mode)) {
        sr_set_error(err, err_size, "%s: not a regular file", label);
        st = SLUICE_ERROR_IO;
    } else if (s.st_size == 0) {
        sr_set_error(err, err_size, "%s: the file is empty", label);
        st = SLUICE_ERROR_IO;
    } else if ((unsigned long long)s.st_size > SR_MESH_MAX_FILE_BYTES) {
        sr_set_error(err, err_size, "%s: %lld bytes, larger than the %u MiB a mesh file may have",
                     label, (long long)s.st_size, SR_MESH_MAX_FILE_BYTES >> 20);
        st = SLUICE_ERROR_LIMIT;
    }
    if (st == SLUICE_OK) {
        *size = (size_t)s.st_size;
        *head_len = fread(head, 1, SR_MESH_GUARD_HEAD_BYTES, f);
        if (*head_len == 0) {
            sr_set_error(err, err_size, "%s: read error", label);
            st = SLUICE_ERROR_IO;
        }
    }
    fclose(f);
    return st;
}

/* A cursor over the head, which ends without a NUL. */
typedef struct cursor {
    const unsigned char *start, *p, *end;
} cursor;

/* Skips white space and '#' comments up to the end of their line. */
static void skip_blank(cursor *c)
{
    while (c->p < c->end) {
        if (isspace(*c->p)) {
            c->p++;
        } else if (*c->p == '#') {
            while (c->p < c->end && *c->p != '\n')
                c->p++;
        } else {
            break;
        }
    }
}

/* Copies the next token (cut to `n` - 1 bytes) into `tok`. */
static void token(cursor *c, char *tok, size_t n)
{
    skip_blank(c);
    size_t k = 0;
    for (; c->p < c->end && !isspace(*c->p); c->p++) {
        if (k + 1 < n)
            tok[k++] = (char)*c->p;
    }
    tok[k] = '\0';
}

/* Reads an unsigned decimal number, saturating at ULLONG_MAX / 16 (a count
 * that large fails every check below anyway). 0 when there is none. */
static int number(cursor *c, unsigned long long *out)
{
    skip_blank(c);
    if (c->p >= c->end || !isdigit(*c->p))
        return 0;
    unsigned long long v = 0;
    for (; c->p < c->end && isdigit(*c->p); c->p++)
        v = v >= (~0ull >> 4) / 10 ? (~0ull >> 4) : v * 10 + (unsigned)(*c->p - '0');
    *out = v;
    return 1;
}

/* OFF (assimp's header: [ST][C][N][4][n]OFF, a dimension after nOFF, then
 * the vertex and face counts): every vertex takes at least three numbers
 * ("0 0 0\n", 6 bytes) and every face at least one ("0\n", 2 bytes). */
static sluice_status check_off(cursor c, size_t size, const char *label, char *err, size_t err_size)
{
    char tok[16];
    token(&c, tok, sizeof tok);
    size_t tl = strlen(tok);
    if (tl < 3 || tl > 9 || strcmp(tok + tl - 3, "OFF") != 0)
        return SLUICE_OK;
    unsigned long long dim = 3, nv = 0, nf = 0;
    if (strchr(tok, 'n') && !number(&c, &dim))
        return SLUICE_OK; /* assimp reports the bad header */
    if (!number(&c, &nv) || !number(&c, &nf))
        return SLUICE_OK;
    unsigned long long per_vertex = 2 * (dim > 3 ? dim : 3);
    if (nv > size / per_vertex || nf > size / 2 || nv * per_vertex + nf * 2 > size) {
        sr_set_error(err, err_size,
                     "%s: the OFF header declares %llu vertices and %llu faces, more than a file "
                     "of %zu bytes holds",
                     label, nv, nf, size);
        return SLUICE_ERROR_LIMIT;
    }
    return SLUICE_OK;
}

/* PLY: the header must end (end_header) within SR_MESH_GUARD_HEAD_BYTES
 * and be text: assimp 5.2's PLY parser loops forever on a header that ends
 * without it or holds a NUL. Every instance of an element takes at least
 * one byte (a line in ASCII, a property in binary). */
static sluice_status check_ply(cursor c, size_t size, const char *label, char *err, size_t err_size)
{
    char tok[32];
    token(&c, tok, sizeof tok);
    if (strcmp(tok, "ply") != 0 && strcmp(tok, "PLY") != 0)
        return SLUICE_OK;
    unsigned long long total = 0;
    int ended = 0;
    for (const unsigned char *q = c.p; q < c.end && !ended; ++q) {
        if (*q == 0 || (*q < 32 && !isspace(*q)) || *q == 127) {
            sr_set_error(err, err_size, "%s: the PLY header holds a control character (byte %zu)",
                         label, (size_t)(q - c.start));
            return SLUICE_ERROR_IO;
        }
        ended = (size_t)(c.end - q) >= 10 && memcmp(q, "end_header", 10) == 0;
    }
    if (!ended) {
        sr_set_error(err, err_size, "%s: the PLY header has no end_header in its first %u bytes",
                     label, SR_MESH_GUARD_HEAD_BYTES);
        return SLUICE_ERROR_IO;
    }
    while (c.p < c.end) {
        token(&c, tok, sizeof tok);
        if (strcmp(tok, "end_header") == 0)
            break;
        if (strcmp(tok, "element") != 0)
            continue;
        char name[32];
        unsigned long long n = 0;
        token(&c, name, sizeof name);
        if (!number(&c, &n))
            continue;
        total += n;
        if (n > size || total > size) {
            sr_set_error(err, err_size,
                         "%s: the PLY header declares %llu '%s' elements, more than a file of "
                         "%zu bytes holds",
                         label, n, name, size);
            return SLUICE_ERROR_LIMIT;
        }
    }
    return SLUICE_OK;
}

sluice_status sr_mesh_guard_header(const unsigned char *head, size_t head_len, size_t size,
                                   const char *label, char *err, size_t err_size)
{
    cursor c = {head, head, head + head_len};
    sluice_status st = check_off(c, size, label, err, err_size);
    if (st == SLUICE_OK)
        st = check_ply(c, size, label, err, err_size);
    return st;
}
