/* Tests of the build-log digest (runtime/src/build_log.h): every vendor's
 * sample log in tests/data/build_log/ (PoCL's captured here, NVIDIA's and
 * AMD's written from their published format; see each file's header) comes
 * out as `FILE:LINE:COL: error: MESSAGE` lines, first error first, with our
 * file name for the vendor's placeholder; plus small cases written inline.
 * No OpenCL: test_runtime checks the same against a real PoCL build.
 *
 * Usage: test_build_log DATA_DIR (tests/data/build_log). */
#include "build_log.h"
#include "check.h"

#include <ctype.h>

static const char *data_dir = "";

/* Reads DATA_DIR/NAME (malloc'd; NULL when missing). */
static char *read_data(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", data_dir, name);
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL, "cannot open %s", path);
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    rewind(f);
    char *text = malloc(n > 0 ? (size_t)n + 1 : 1);
    size_t got = text && n > 0 ? fread(text, 1, (size_t)n, f) : 0;
    if (text)
        text[got] = 0;
    fclose(f);
    return text;
}

/* Is `line` (up to its newline) `FILE:LINE:COL: error: MESSAGE`, FILE not
 * empty and MESSAGE not empty? */
static int is_error_line(const char *line)
{
    const char *end = strchr(line, '\n');
    size_t len = end ? (size_t)(end - line) : strlen(line);
    const char *tag = strstr(line, ": error: ");
    if (!tag || (size_t)(tag - line) >= len || tag + 9 >= line + len)
        return 0;
    const char *p = tag;
    int numbers = 0;
    while (numbers < 2) {
        const char *q = p;
        while (q > line && isdigit((unsigned char)q[-1]))
            --q;
        if (q == p || q == line || q[-1] != ':')
            return 0;
        p = q - 1;
        numbers++;
    }
    return p > line;
}

/* One vendor's sample: the digest equals NAME.expected, every line has the
 * shape, the first is the log's first error; `want_more`: whether the log
 * holds source excerpts worth showing. With warnings, the same errors lead
 * and the warnings follow, each once. */
static void check_sample(const char *vendor, int want_more)
{
    char name[64];
    snprintf(name, sizeof name, "%s.log", vendor);
    char *file = read_data(name);
    snprintf(name, sizeof name, "%s.expected", vendor);
    char *expected = read_data(name);
    if (!file || !expected) {
        free(file);
        free(expected);
        return;
    }
    /* The sample's header (where it comes from) ends at a line "----". */
    char *log = strstr(file, "\n----\n");
    CHECK(log != NULL, "%s.log has no ---- line after its header", vendor);
    log = log ? log + 6 : file;

    bool more = !want_more;
    char *got = sl_build_log_digest(log, "broken.cl", false, &more);
    CHECK(got && strcmp(got, expected) == 0, "%s: digest\n[%s]\nexpected\n[%s]", vendor,
          got ? got : "(null)", expected);
    CHECK(more == (bool)want_more, "%s: more is %d", vendor, (int)more);
    int lines = 0;
    for (const char *l = got; l && *l; l = strchr(l, '\n') + 1) {
        CHECK(is_error_line(l), "%s: line %d has not the shape FILE:LINE:COL: error: MSG: %s",
              vendor, lines + 1, l);
        CHECK(strncmp(l, "broken.cl:", 10) == 0, "%s: our file name: %s", vendor, l);
        lines++;
    }
    CHECK(lines == 2, "%s: %d error lines", vendor, lines);
    CHECK(got && strncmp(got,
                         "broken.cl:8:16: error: use of undeclared identifier "
                         "'undefined_thing'\n",
                         strlen("broken.cl:8:16: error: use of undeclared identifier "
                                "'undefined_thing'\n")) == 0,
          "%s: the first error first: %s", vendor, got ? got : "(null)");

    char *all = sl_build_log_digest(log, "broken.cl", true, NULL);
    CHECK(all && strncmp(all, expected, strlen(expected)) == 0, "%s: errors lead: %s", vendor,
          all ? all : "(null)");
    const char *warn = "broken.cl:2:2: warning: check the limits below\n";
    const char *w = all ? strstr(all, warn) : NULL;
    CHECK(w && !strstr(w + 1, warn), "%s: the #warning once: %s", vendor, all ? all : "(null)");
    CHECK(all && strstr(all, "broken.cl:6:18: warning: implicit conversion"),
          "%s: the conversion warning: %s", vendor, all ? all : "(null)");
    free(all);
    free(got);
    free(file);
    free(expected);
}

/* The digest of `log` (errors only) is `want`. */
static void check_digest(const char *log, const char *want, const char *what)
{
    char *got = sl_build_log_digest(log, "my.cl", false, NULL);
    CHECK(got && strcmp(got, want) == 0, "%s: got [%s], want [%s]", what, got ? got : "(null)",
          want);
    free(got);
}

static void check_cases(void)
{
    check_digest("", "", "empty log");
    check_digest(NULL, "", "no log");
    check_digest("warning: my.cl:1:2: only a warning\n", "", "warnings only");
    check_digest(":12:5: error: old NVIDIA\n", "my.cl:12:5: error: old NVIDIA\n",
                 "empty file name");
    check_digest("1:12:5: error: Intel\n", "my.cl:12:5: error: Intel\n", "source index");
    check_digest("<source>:3:4: error: a\r\n<stdin>:5:6: error: b\r\n",
                 "my.cl:3:4: error: a\nmy.cl:5:6: error: b\n", "placeholders, CRLF");
    check_digest("other.h:7:1: fatal error: 'x.h' file not found\n",
                 "other.h:7:1: error: 'x.h' file not found\n", "fatal error, own file kept");
    check_digest("my.cl:3: error: no column\n", "my.cl:3: error: no column\n", "no column");
    check_digest("C:\\k\\my.cl:3:4: error: drive\n", "C:\\k\\my.cl:3:4: error: drive\n",
                 "a colon in the file name");
    check_digest("error: Compiler frontend failed (error code 59)\n",
                 "my.cl: error: Compiler frontend failed (error code 59)\n", "unlocated only");
    check_digest("<kernel>:2:3: error: real\nerror: Compiler frontend failed\n",
                 "my.cl:2:3: error: real\n", "unlocated dropped after located");
    check_digest("    x = \"a:1: error: b\";\n  y:2: error: c\n", "",
                 "source excerpts are no diagnostics");
    check_digest("my.cl:4:1: note: here\nmy.cl:5:1: remark: r\n", "", "notes dropped");
    check_digest("In file included from my.cl:1:\nmy.h:2:3: error: in a header\n",
                 "my.h:2:3: error: in a header\n", "include stack");
    bool more = true;
    char *d =
        sl_build_log_digest("error: my.cl:1:1: x\n\n3 errors generated.\n", "my.cl", false, &more);
    CHECK(!more, "chatter and blank lines are not more");
    free(d);
    d = sl_build_log_digest("my.cl:1:1: error: x\n  x;\n  ^\n", "my.cl", false, &more);
    CHECK(more, "source excerpts are more");
    free(d);
    CHECK(sl_build_log_is_count("2 warnings generated.\n", 22), "a count");
    CHECK(sl_build_log_is_count("1 warning and 1 error generated.", 32), "a count of both");
    CHECK(!sl_build_log_is_count("2 kernels generated.\nan error", 20), "no count past the line");
}

/* The log NVIDIA's compiler wrote for a source it was handed with #line
 * directives, which it ignores (nvidia-h100.log): relocated through a source
 * with the directives on the same lines (1 and 531), its locations name the
 * user's file and lines, and its digest leads with them. Also: lines before
 * any directive, a directive's own start line, a broken directive, no
 * source, and lines that already name a file. */
static void check_relocate(void)
{
    char *file = read_data("nvidia-h100.log");
    char *expected = read_data("nvidia-h100.expected");
    char *source = malloc(2048);
    if (!file || !expected || !source) {
        free(file);
        free(expected);
        free(source);
        return;
    }
    char *p = source + sprintf(source, "#line 1 \"sluice.cl\"\n");
    for (int line = 2; line < 531; ++line)
        *p++ = '\n';
    sprintf(p, "#line 1 \"two.cl\"\n#include \"sluice.cl\"\n#warning sluice test warning\n");
    char *log = strstr(file, "\n----\n");
    CHECK(log != NULL, "nvidia-h100.log has no ---- line after its header");
    log = log ? log + 6 : file;
    char *moved = sl_build_log_relocate(log, source);
    CHECK(moved && strncmp(moved, "two.cl:2:2: warning: sluice test warning\n#warning", 48) == 0,
          "NVIDIA, relocated, source lines kept: [%s]", moved ? moved : "(null)");
    char *got = sl_build_log_digest(moved, "two.cl", false, NULL);
    CHECK(got && strcmp(got, expected) == 0, "NVIDIA, relocated digest: got [%s], want [%s]",
          got ? got : "(null)", expected);
    free(got);
    free(moved);
    moved = sl_build_log_relocate(log, NULL);
    CHECK(moved && strcmp(moved, log) == 0, "no source: the log unchanged");
    free(moved);
    moved = sl_build_log_relocate("<kernel>:1:2: error: x\n<kernel>:3:4: error: y\n:9: note: z\n"
                                  "my.cl:3:1: error: named\n  <kernel>:3:4: excerpt",
                                  "#line 1 \"sluice.cl\"\nint a;\nint b;\n#line 7 \"my.cl\"\nz\n"
                                  "w\n#line 2 \"bad\nq\n");
    CHECK(moved && strcmp(moved, "<kernel>:1:2: error: x\nsluice.cl:2:4: error: y\nmy.cl:11: note: "
                                 "z\nmy.cl:3:1: error: named\n  <kernel>:3:4: excerpt") == 0,
          "before any directive, after one, no column, named, excerpt: [%s]",
          moved ? moved : "(null)");
    free(moved);
    free(source);
    free(file);
    free(expected);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_build_log DATA_DIR\n");
        return 2;
    }
    data_dir = argv[1];
    check_sample("pocl", 0);
    check_sample("nvidia", 1);
    check_sample("amd", 1);
    check_cases();
    check_relocate();
    return check_summary();
}
