/* See scene_mesh_guard.h. */
#include "scene_mesh_guard.h"
#include "app_error.h"
#include "scene.h"

#include <ctype.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

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

/* Skips to the start of the next line. */
static void skip_line(cursor *c)
{
    while (c->p < c->end && *c->p != '\n')
        c->p++;
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
 * the vertex and face counts; in a file named .off the header may be
 * missing): every vertex takes at least three numbers
 * ("0 0 0\n", 6 bytes) and every face at least one ("0\n", 2 bytes). */
static sluice_status check_off(cursor c, int is_off, size_t size, const char *label, char *err,
                               size_t err_size)
{
    const cursor start = c;
    /* as assimp reads it: the prefix letters, "OFF", and the numbers right
     * after it ("OFF2044" counts from 2044) */
    skip_blank(&c);
    int dimension = 0;
    while (c.p < c.end && *c.p && strchr("STCN4n", *c.p)) {
        dimension |= *c.p == 'n';
        c.p++;
    }
    if (c.end - c.p >= 3 && memcmp(c.p, "OFF", 3) == 0)
        c.p += 3;
    else if (is_off)
        c = start; /* assimp reads a file named .off without the header too */
    else
        return SLUICE_OK;
    /* assimp's tokenizer differs in corners (comments, glued tokens): as a
     * bound that does not depend on it, none of the first four numbers of
     * the header may exceed what the file holds at two bytes an element */
    cursor q = start;
    for (int runs = 0; runs < 4 && q.p < q.end && q.p - q.start < 256; ++q.p) {
        if (!isdigit(*q.p))
            continue;
        unsigned long long v = 0;
        for (; q.p < q.end && isdigit(*q.p); q.p++)
            v = v >= (~0ull >> 4) / 10 ? (~0ull >> 4) : v * 10 + (unsigned)(*q.p - '0');
        runs++;
        if (v > size / 2) {
            sr_set_error(err, err_size,
                         "%s: the OFF header's count %llu is more than a file of %zu bytes holds",
                         label, v, size);
            return SLUICE_ERROR_LIMIT;
        }
    }
    unsigned long long dim = 3, nv = 0, nf = 0;
    if (dimension && !number(&c, &dim))
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

/* The bytes after the header, from memory or a file (read in blocks). */
typedef struct body {
    const unsigned char *mem; /* the whole data, or NULL: read `f` */
    FILE *f;
    size_t pos, size; /* offsets in the whole data */
    unsigned char block[4096];
    size_t block_pos, block_len;
} body;

/* Reads n <= 8 bytes at the current position; 0 past the end. */
static int body_read(body *b, unsigned char *out, size_t n)
{
    if (n > b->size - b->pos)
        return 0;
    if (b->mem) {
        memcpy(out, b->mem + b->pos, n);
    } else {
        if (b->pos < b->block_pos || b->pos + n > b->block_pos + b->block_len) {
            if (fseek(b->f, (long)b->pos, SEEK_SET) != 0)
                return 0;
            b->block_pos = b->pos;
            b->block_len = fread(b->block, 1, sizeof b->block, b->f);
            if (b->block_len < n)
                return 0;
        }
        memcpy(out, b->block + (b->pos - b->block_pos), n);
    }
    b->pos += n;
    return 1;
}

static int body_skip(body *b, unsigned long long n)
{
    if (n > b->size - b->pos)
        return 0;
    b->pos += (size_t)n;
    return 1;
}

/* Size in bytes of a PLY scalar type (the names assimp knows), 0 if none. */
static unsigned ply_type_size(const char *t)
{
    static const char *const names[] = {"char",  "uchar",   "int8",   "uint8",  "short", "ushort",
                                        "int16", "uint16",  "int",    "uint",   "int32", "uint32",
                                        "float", "float32", "double", "float64"};
    static const unsigned sizes[] = {1, 1, 1, 1, 2, 2, 2, 2, 4, 4, 4, 4, 4, 4, 8, 8};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
        if (strcmp(t, names[i]) == 0)
            return sizes[i];
    }
    return 0;
}

#define PLY_MAX_ELEMENTS 64
#define PLY_MAX_PROPERTIES 256

typedef struct ply_property {
    unsigned count_size; /* 0: a scalar of item_size bytes; else a list's count */
    int count_signed;
    unsigned item_size;
} ply_property;

typedef struct ply_element {
    char name[32];
    unsigned long long count;
    unsigned first, properties;
} ply_element;

/* Walks a binary PLY's data as its header describes it: assimp 5.2 reads
 * binary PLY data without checking where it ends, so a list count or an
 * element count larger than the data makes it read past its buffer. */
static sluice_status walk_binary_ply(body *b, int big_endian, const ply_element *el, size_t ne,
                                     const ply_property *pr, const char *label, char *err,
                                     size_t err_size)
{
    for (size_t e = 0; e < ne; ++e) {
        for (unsigned long long i = 0; i < el[e].count; ++i) {
            for (unsigned k = el[e].first; k < el[e].first + el[e].properties; ++k) {
                int ok;
                if (!pr[k].count_size) {
                    ok = body_skip(b, pr[k].item_size);
                } else {
                    unsigned char c[8];
                    ok = body_read(b, c, pr[k].count_size);
                    unsigned long long n = 0;
                    for (unsigned j = 0; ok && j < pr[k].count_size; ++j)
                        n = n << 8 | c[big_endian ? j : pr[k].count_size - 1 - j];
                    int negative =
                        pr[k].count_signed && (c[big_endian ? 0 : pr[k].count_size - 1] & 0x80);
                    if (ok && negative) {
                        sr_set_error(err, err_size,
                                     "%s: PLY element '%s' %llu: a list with a negative count",
                                     label, el[e].name, i);
                        return SLUICE_ERROR_IO;
                    }
                    ok = ok && body_skip(b, n * pr[k].item_size);
                }
                if (!ok) {
                    sr_set_error(err, err_size,
                                 "%s: the binary PLY data ends within element '%s' %llu of %llu",
                                 label, el[e].name, i, el[e].count);
                    return SLUICE_ERROR_IO;
                }
            }
        }
    }
    return SLUICE_OK;
}

static int body_getc(body *b);

/* Reads the next word of the current line of ASCII PLY data as an unsigned
 * count, as assimp's strtoul10 does (the leading digits, saturating; a
 * leading '-' gives ~0ull >> 4). 1: a word; 0: the line ended (its '\n' is
 * consumed); -1: the data ended; -2: a NUL byte (assimp's line reader
 * ends a line there, which shifts every later line). */
static int ascii_word(body *b, unsigned long long *out)
{
    int ch;
    while ((ch = body_getc(b)) >= 0 && ch != '\n' && isspace(ch)) {
    }
    if (ch < 0)
        return -1;
    if (ch == '\n')
        return 0;
    if (ch == 0)
        return -2;
    unsigned long long v = 0;
    int digits = 1;
    if (ch == '-')
        v = ~0ull >> 4, digits = 0;
    for (; ch >= 0 && !isspace(ch); ch = body_getc(b)) {
        if (ch == 0)
            return -2;
        digits = digits && isdigit(ch);
        if (digits)
            v = v >= (~0ull >> 4) / 10 ? (~0ull >> 4) : v * 10 + (unsigned)(ch - '0');
    }
    if (ch == '\n')
        b->pos--; /* the line's end is the next call's */
    *out = v;
    return 1;
}

/* Walks an ASCII PLY's data line by line (an element instance a line, as
 * assimp reads it): assimp 5.2 reserves room for a list's count before
 * reading its items, so a face claiming 244444444444 corners takes all
 * memory. A list may not count more items than the rest of the file holds
 * (two bytes an item: a digit and a separator). */
static sluice_status walk_ascii_ply(body *b, const ply_element *el, size_t ne,
                                    const ply_property *pr, const char *label, char *err,
                                    size_t err_size)
{
    for (size_t e = 0; e < ne; ++e) {
        for (unsigned long long i = 0; i < el[e].count; ++i) {
            int r = 1;
            unsigned long long n = 0;
            for (unsigned k = el[e].first; r > 0 && k < el[e].first + el[e].properties; ++k) {
                r = ascii_word(b, &n);
                if (r <= 0 || !pr[k].count_size)
                    continue;
                if (n > (b->size - b->pos) / 2) {
                    sr_set_error(err, err_size,
                                 "%s: PLY element '%s' %llu: a list of %llu items, more than the "
                                 "rest of the file holds",
                                 label, el[e].name, i, n);
                    return SLUICE_ERROR_LIMIT;
                }
                unsigned long long item;
                for (unsigned long long j = 0; r > 0 && j < n; ++j)
                    r = ascii_word(b, &item);
            }
            /* the rest of the instance's line */
            while (r > 0)
                r = ascii_word(b, &n);
            if (r == -2) {
                sr_set_error(err, err_size, "%s: an ASCII PLY file is text, but byte %zu is NUL",
                             label, b->pos - 1);
                return SLUICE_ERROR_IO;
            }
            if (r < 0)
                return SLUICE_OK; /* short data: assimp reads what is there */
        }
    }
    return SLUICE_OK;
}

/* PLY: the header must end (an end_header line) within
 * SR_MESH_GUARD_HEAD_BYTES and be printable text, tabs and line ends:
 * assimp 5.2's PLY parser loops forever on a header without that line (a
 * NUL, a vertical tab or a missing newline hide it). Property types must be ones assimp knows.
 * Every element instance takes at least one byte (a line in ASCII, a
 * property in binary); binary data is walked to its end (walk_binary_ply). */
static sluice_status check_ply(cursor c, int is_ply, body *b, const char *label, char *err,
                               size_t err_size)
{
    /* assimp takes data that starts with "ply" in any case for PLY, and a
     * file named .ply even when blanks or NUL bytes come first */
    const unsigned char *q0 = c.p;
    while (q0 < c.end && (isspace(*q0) || *q0 == 0))
        q0++;
    int magic =
        c.end - q0 >= 3 && tolower(q0[0]) == 'p' && tolower(q0[1]) == 'l' && tolower(q0[2]) == 'y';
    if (!magic && !is_ply)
        return SLUICE_OK;
    if (!magic || q0 != c.p) {
        sr_set_error(err, err_size, "%s: a PLY file starts with \"ply\"", label);
        return SLUICE_ERROR_IO;
    }
    /* the header ends at a line that starts with end_header */
    const unsigned char *end_header = NULL;
    int line_start = 1;
    for (const unsigned char *q = c.p; q < c.end && !end_header; ++q) {
        if ((*q < 32 && *q != '\t' && *q != '\r' && *q != '\n') || *q >= 127) {
            sr_set_error(err, err_size,
                         "%s: the PLY header holds a control or non-ASCII byte (byte %zu)", label,
                         (size_t)(q - c.start));
            return SLUICE_ERROR_IO;
        }
        if (line_start && (size_t)(c.end - q) >= 10 && memcmp(q, "end_header", 10) == 0) {
            /* assimp's line ends at \r or \n; anything else on the line
             * makes it read past the header looking for end_header */
            const unsigned char *r = q + 10;
            while (r < c.end && (*r == ' ' || *r == '\t'))
                r++;
            if (r < c.end && (*r == '\r' || *r == '\n'))
                end_header = q;
        }
        line_start = *q == '\n' || (line_start && (*q == ' ' || *q == '\t'));
    }
    if (!end_header) {
        sr_set_error(err, err_size,
                     "%s: the PLY header has no end_header line in its first %u bytes", label,
                     SR_MESH_GUARD_HEAD_BYTES);
        return SLUICE_ERROR_IO;
    }
    char tok[32];
    skip_line(&c); /* "ply" */
    static const ply_element no_element;
    ply_element el[PLY_MAX_ELEMENTS];
    ply_property pr[PLY_MAX_PROPERTIES];
    size_t ne = 0, np = 0;
    int format = 0, binary = 0, big_endian = 0;
    unsigned long long total = 0;
    const unsigned char *head_end = c.end;
    c.end = end_header;
    while (c.p < c.end) {
        token(&c, tok, sizeof tok);
        if (!tok[0])
            break;
        if (strcmp(tok, "format") == 0) {
            token(&c, tok, sizeof tok);
            binary = strncmp(tok, "binary_", 7) == 0;
            big_endian = strcmp(tok, "binary_big_endian") == 0;
            if (format++ || (strcmp(tok, "ascii") != 0 &&
                             strcmp(tok, "binary_little_endian") != 0 && !big_endian)) {
                sr_set_error(err, err_size, "%s: PLY format '%s' %s", label, tok,
                             format > 1 ? "given twice" : "unknown");
                return SLUICE_ERROR_IO;
            }
            skip_line(&c);
        } else if (strcmp(tok, "comment") == 0 || strcmp(tok, "obj_info") == 0) {
            skip_line(&c);
        } else if (strcmp(tok, "element") == 0) {
            if (ne == PLY_MAX_ELEMENTS) {
                sr_set_error(err, err_size, "%s: more than %d PLY elements", label,
                             PLY_MAX_ELEMENTS);
                return SLUICE_ERROR_LIMIT;
            }
            ply_element *e = &el[ne++];
            *e = no_element;
            e->first = (unsigned)np;
            token(&c, e->name, sizeof e->name);
            int word = isalpha((unsigned char)e->name[0]) || e->name[0] == '_';
            for (const char *q = e->name; *q && word; ++q)
                word = isalnum((unsigned char)*q) || *q == '_' || *q == '-';
            if (!word) {
                /* assimp reads a name that starts with digits as the count */
                sr_set_error(err, err_size, "%s: PLY element name '%s' is not a word", label,
                             e->name);
                return SLUICE_ERROR_IO;
            }
            for (size_t k = 0; k + 1 < ne; ++k) {
                /* assimp sizes its arrays by the first and fills them
                 * from all: a heap overflow */
                if (strcmp(el[k].name, e->name) == 0) {
                    sr_set_error(err, err_size, "%s: PLY element '%s' declared twice", label,
                                 e->name);
                    return SLUICE_ERROR_IO;
                }
            }
            if (!number(&c, &e->count)) {
                sr_set_error(err, err_size, "%s: PLY element '%s' without a count", label, e->name);
                return SLUICE_ERROR_IO;
            }
            total += e->count;
            if (e->count > b->size || total > b->size) {
                sr_set_error(err, err_size,
                             "%s: the PLY header declares %llu '%s' elements, more than a file "
                             "of %zu bytes holds",
                             label, e->count, e->name, b->size);
                return SLUICE_ERROR_LIMIT;
            }
            skip_line(&c);
        } else if (strcmp(tok, "property") == 0) {
            if (!ne || np == PLY_MAX_PROPERTIES) {
                sr_set_error(err, err_size, "%s: %s", label,
                             ne ? "more than 256 PLY properties"
                                : "a PLY property outside any element");
                return ne ? SLUICE_ERROR_LIMIT : SLUICE_ERROR_IO;
            }
            ply_property *p = &pr[np++];
            el[ne - 1].properties++;
            token(&c, tok, sizeof tok);
            p->count_size = 0;
            p->count_signed = 0;
            if (strcmp(tok, "list") == 0) {
                token(&c, tok, sizeof tok);
                p->count_size = ply_type_size(tok);
                p->count_signed = tok[0] != 'u';
                if (p->count_size && (strncmp(tok, "float", 5) == 0 || strcmp(tok, "double") == 0))
                    p->count_size = 0; /* a list counted by a float */
                if (!p->count_size) {
                    sr_set_error(err, err_size, "%s: PLY list count type '%s' is not an integer",
                                 label, tok);
                    return SLUICE_ERROR_IO;
                }
                token(&c, tok, sizeof tok);
            }
            p->item_size = ply_type_size(tok);
            if (!p->item_size) {
                sr_set_error(err, err_size, "%s: unknown PLY property type '%s'", label, tok);
                return SLUICE_ERROR_IO;
            }
            skip_line(&c); /* the property's name */
        } else {
            skip_line(&c); /* free text: Blender writes "Created by ..." */
        }
    }
    if (!format) {
        sr_set_error(err, err_size, "%s: the PLY header has no format line", label);
        return SLUICE_ERROR_IO;
    }

    /* the data starts after the end_header line (blanks, then "\n" or
     * "\r\n"; the head holds that line, as the scan above checked) */
    const unsigned char *q = end_header + 10;
    while (*q == ' ' || *q == '\t')
        q++;
    q += *q == '\r';
    q += q < head_end && *q == '\n';
    b->pos = (size_t)(q - c.start);
    b->block_pos = b->block_len = 0;
    return binary ? walk_binary_ply(b, big_endian, el, ne, pr, label, err, err_size)
                  : walk_ascii_ply(b, el, ne, pr, label, err, err_size);
}

/* The next byte of `b`, read from the start onwards; -1 at the end. */
static int body_getc(body *b)
{
    if (b->pos >= b->size)
        return -1;
    if (b->mem)
        return b->mem[b->pos++];
    if (b->pos >= b->block_pos + b->block_len) {
        if (fseek(b->f, (long)b->pos, SEEK_SET) != 0)
            return -1;
        b->block_pos = b->pos;
        b->block_len = fread(b->block, 1, sizeof b->block, b->f);
        if (b->block_len == 0)
            return -1;
    }
    return b->block[b->pos++ - b->block_pos];
}

/* Reads the next line of text into `line` (cut to `n` - 1 bytes, without
 * its end); 0 at the end of the data, -1 at a NUL byte. */
static int next_line(body *b, char *line, size_t n)
{
    size_t k = 0;
    int ch = body_getc(b);
    if (ch < 0)
        return 0;
    for (; ch >= 0 && ch != '\n'; ch = body_getc(b)) {
        if (ch == 0)
            return -1;
        if (k + 1 < n)
            line[k++] = (char)ch;
    }
    while (k && isspace((unsigned char)line[k - 1]))
        k--;
    line[k] = '\0';
    return 1;
}

/* The statement's keyword: the line's first word (`line` is modified). */
static char *keyword(char *line, char **rest)
{
    while (*line == ' ' || *line == '\t')
        line++;
    char *e = line;
    while (*e && *e != ' ' && *e != '\t')
        e++;
    *rest = e;
    if (*e) {
        *e = '\0';
        *rest = e + 1;
        while (**rest == ' ' || **rest == '\t')
            (*rest)++;
    }
    return line;
}

/* An MTL library an OBJ names: assimp 5.2's MTL parser dereferences a NULL
 * material for a texture statement (map_Kd, bump, norm, ...) before the
 * first newmtl, and stops at a NUL byte: only comments may come first. */
static sluice_status check_mtl(FILE *f, const char *mtl, const char *label, char *err,
                               size_t err_size)
{
    body *b = calloc(1, sizeof *b);
    if (!b) {
        sr_set_error(err, err_size, "%s: out of memory", label);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    struct stat s;
    sluice_status st = SLUICE_OK;
    if (fstat(fileno(f), &s) != 0 || !S_ISREG(s.st_mode) ||
        (unsigned long long)s.st_size > SR_MESH_MAX_FILE_BYTES) {
        sr_set_error(err, err_size, "%s: MTL library %s: not a regular file of at most %u MiB",
                     label, mtl, SR_MESH_MAX_FILE_BYTES >> 20);
        st = SLUICE_ERROR_IO;
    }
    b->f = f;
    b->size = st == SLUICE_OK ? (size_t)s.st_size : 0;
    char line[256];
    int r;
    size_t no = 0;
    while (st == SLUICE_OK && (r = next_line(b, line, sizeof line)) != 0) {
        no++;
        if (r < 0) {
            sr_set_error(err, err_size, "%s: MTL library %s: line %zu holds a NUL byte", label, mtl,
                         no);
            st = SLUICE_ERROR_IO;
            break;
        }
        char *rest;
        const char *kw = keyword(line, &rest);
        if (strcmp(kw, "newmtl") == 0)
            break;
        if (*kw && *kw != '#') {
            sr_set_error(err, err_size,
                         "%s: MTL library %s: line %zu: '%s' before the first newmtl", label, mtl,
                         no, kw);
            st = SLUICE_ERROR_IO;
        }
    }
    /* after the first newmtl a NUL byte still stops assimp's parser short */
    for (int ch; st == SLUICE_OK && (ch = body_getc(b)) >= 0;) {
        if (ch == 0) {
            sr_set_error(err, err_size, "%s: MTL library %s: byte %zu is NUL", label, mtl,
                         b->pos - 1);
            st = SLUICE_ERROR_IO;
        }
    }
    free(b);
    return st;
}

/* Opens and checks the MTL library `name` relative to `dir` ("" or ending
 * in '/'); *found says whether it exists. */
static sluice_status check_mtl_at(const char *dir, const char *name, int *found, const char *label,
                                  char *err, size_t err_size)
{
    size_t n = strlen(dir) + strlen(name) + 1;
    char *path = malloc(n);
    if (!path) {
        sr_set_error(err, err_size, "%s: out of memory", label);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    snprintf(path, n, "%s%s", dir, name);
    FILE *f = fopen(path, "rb");
    *found = f != NULL;
    sluice_status st = f ? check_mtl(f, name, label, err, err_size) : SLUICE_OK;
    if (f)
        fclose(f);
    free(path);
    return st;
}

/* OBJ is text, and its MTL libraries (mtllib) are read with it. assimp
 * 5.2's OBJ parser reads past its buffer on a NUL byte (it takes NUL for
 * the end of the data). When a library is missing assimp reads the OBJ's
 * name with "mtl" for "obj" instead; from memory that name is the memory
 * buffer's own, so the OBJ itself is read as an MTL library: OBJ data from
 * memory may not name one. `path` is the OBJ file, or NULL for memory. */
static sluice_status check_obj(body *b, const char *path, const char *label, char *err,
                               size_t err_size)
{
    char *dir = NULL;
    if (path) {
        const char *slash = strrchr(path, '/');
        size_t dl = slash ? (size_t)(slash - path) + 1 : 0;
        dir = malloc(dl + 1);
        if (!dir) {
            sr_set_error(err, err_size, "%s: out of memory", label);
            return SLUICE_ERROR_OUT_OF_MEMORY;
        }
        memcpy(dir, path, dl);
        dir[dl] = '\0';
    }
    b->pos = 0;
    b->block_pos = b->block_len = 0;
    char line[1100];
    int r, missing = 0;
    size_t no = 0;
    sluice_status st = SLUICE_OK;
    while (st == SLUICE_OK && (r = next_line(b, line, sizeof line)) != 0) {
        no++;
        if (r < 0) {
            sr_set_error(err, err_size, "%s: line %zu: an OBJ file is text, but holds a NUL byte",
                         label, no);
            st = SLUICE_ERROR_IO;
            break;
        }
        char *rest;
        if (strcmp(keyword(line, &rest), "mtllib") != 0 || !*rest)
            continue;
        if (!path) {
            sr_set_error(err, err_size,
                         "%s: line %zu: OBJ data read from memory may not name an MTL library "
                         "(assimp would read the data itself as one)",
                         label, no);
            st = SLUICE_ERROR_IO;
        } else {
            int found = 0;
            st = check_mtl_at(dir, rest, &found, label, err, err_size);
            missing |= !found;
        }
    }
    size_t pl = path ? strlen(path) : 0;
    if (st == SLUICE_OK && missing && pl >= 3) {
        /* assimp's fallback: the OBJ's own name, "obj" replaced by "mtl" */
        char *fb = malloc(pl + 1);
        if (!fb) {
            sr_set_error(err, err_size, "%s: out of memory", label);
            st = SLUICE_ERROR_OUT_OF_MEMORY;
        } else {
            memcpy(fb, path, pl - 3);
            memcpy(fb + pl - 3, "mtl", 4);
            int found = 0;
            st = check_mtl_at("", fb, &found, label, err, err_size);
            free(fb);
        }
    }
    free(dir);
    return st;
}

/* Non-zero when `ext` (a file extension or format hint) is `want`, in any
 * case. */
static int is_format(const char *ext, const char *want)
{
    if (!ext)
        return 0;
    for (; *ext && *want; ++ext, ++want) {
        if (tolower((unsigned char)*ext) != *want)
            return 0;
    }
    return !*ext && !*want;
}

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Binary glTF: assimp allocates the lengths its header and chunk headers
 * give before reading; each must fit the file. */
static sluice_status check_glb(const unsigned char *head, size_t head_len, size_t size,
                               const char *label, char *err, size_t err_size)
{
    if (head_len < 20 || memcmp(head, "glTF", 4) != 0)
        return SLUICE_OK;
    uint32_t total = le32(head + 8), json = le32(head + 12);
    size_t next = 20 + (size_t)json;
    int bad = total > size || json > size - 20;
    if (!bad && next + 8 <= head_len)
        bad = le32(head + next) > size - next - 8; /* the BIN chunk */
    if (bad) {
        sr_set_error(err, err_size, "%s: a glTF binary chunk longer than the file's %zu bytes",
                     label, size);
        return SLUICE_ERROR_LIMIT;
    }
    return SLUICE_OK;
}

/* The checks on the data's first bytes (`head`) and the rest (`b`). */
static sluice_status check_header(const unsigned char *head, size_t head_len, body *b,
                                  const char *ext, const char *path, const char *label, char *err,
                                  size_t err_size)
{
    cursor c = {head, head, head + head_len};
    sluice_status st = check_off(c, is_format(ext, "off"), b->size, label, err, err_size);
    if (st == SLUICE_OK)
        st = check_ply(c, is_format(ext, "ply"), b, label, err, err_size);
    if (st == SLUICE_OK)
        st = check_glb(head, head_len, b->size, label, err, err_size);
    if (st == SLUICE_OK && is_format(ext, "obj"))
        st = check_obj(b, path, label, err, err_size);
    return st;
}

sluice_status sr_mesh_guard_file(const char *path, const char *label, char *err, size_t err_size)
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
    unsigned char *head = NULL;
    body *b = NULL;
    if (st == SLUICE_OK) {
        head = malloc(SR_MESH_GUARD_HEAD_BYTES);
        b = calloc(1, sizeof *b);
        if (!head || !b) {
            sr_set_error(err, err_size, "%s: out of memory", label);
            st = SLUICE_ERROR_OUT_OF_MEMORY;
        }
    }
    if (st == SLUICE_OK) {
        size_t n = fread(head, 1, SR_MESH_GUARD_HEAD_BYTES, f);
        b->f = f;
        b->size = (size_t)s.st_size;
        if (n == 0) {
            sr_set_error(err, err_size, "%s: read error", label);
            st = SLUICE_ERROR_IO;
        } else {
            const char *dot = strrchr(path, '.');
            const char *slash = strrchr(path, '/');
            const char *ext = dot && (!slash || dot > slash) ? dot + 1 : NULL;
            st = check_header(head, n, b, ext, path, label, err, err_size);
        }
    }
    free(head);
    free(b);
    fclose(f);
    return st;
}

sluice_status sr_mesh_guard_memory(const void *data, size_t size, const char *hint,
                                   const char *label, char *err, size_t err_size)
{
    if (size == 0) {
        sr_set_error(err, err_size, "%s: the data is empty", label);
        return SLUICE_ERROR_IO;
    }
    if (size > SR_MESH_MAX_FILE_BYTES) {
        sr_set_error(err, err_size, "%s: %zu bytes, larger than the %u MiB a mesh file may have",
                     label, size, SR_MESH_MAX_FILE_BYTES >> 20);
        return SLUICE_ERROR_LIMIT;
    }
    body *b = calloc(1, sizeof *b);
    if (!b) {
        sr_set_error(err, err_size, "%s: out of memory", label);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    b->mem = data;
    b->size = size;
    sluice_status st =
        check_header(data, size < SR_MESH_GUARD_HEAD_BYTES ? size : SR_MESH_GUARD_HEAD_BYTES, b,
                     hint, NULL, label, err, err_size);
    free(b);
    return st;
}
