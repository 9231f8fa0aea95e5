/* Tests of building programs: a build that succeeds prints nothing on
 * stderr, warnings or not, and keeps them in the build log (SLUICE_VERBOSE=1
 * prints them); the library's own kernels build without warnings; and the
 * context's error message is the last call's, "" after a call that
 * succeeded.
 *
 * Usage: test_build KERNELS_DIR (the source tree's kernels/). The suite runs
 * it twice: for the host CPU and with POCL_KERNELLIB_NAME=avx2, PoCL's
 * kernels for AVX2 CPUs without AVX-512 (PoCL builds without those variants
 * ignore it and build for the host again). */
#include "check.h"

#include <dirent.h>
#include <time.h>
#include <unistd.h>

/* What the process writes on stderr (file descriptor 2) between
 * capture_start and capture_stop. No CHECK in between: it prints there. */
typedef struct capture {
    FILE *file;
    int saved;
} capture;

static int capture_start(capture *c)
{
    fflush(stderr);
    c->file = tmpfile();
    c->saved = c->file ? dup(STDERR_FILENO) : -1;
    if (c->saved < 0 || dup2(fileno(c->file), STDERR_FILENO) < 0) {
        if (c->saved >= 0)
            close(c->saved);
        if (c->file)
            fclose(c->file);
        return 0;
    }
    return 1;
}

/* Restores stderr; returns what was written (malloc'd, NUL-terminated). */
static char *capture_stop(capture *c)
{
    fflush(stderr);
    dup2(c->saved, STDERR_FILENO);
    close(c->saved);
    fseek(c->file, 0, SEEK_END);
    long n = ftell(c->file);
    rewind(c->file);
    char *text = malloc(n > 0 ? (size_t)n + 1 : 1);
    size_t got = text && n > 0 ? fread(text, 1, (size_t)n, c->file) : 0;
    if (text)
        text[got] = 0;
    fclose(c->file);
    return text;
}

/* A kernel whose build warns; `nonce` makes its code new, so that PoCL
 * compiles it afresh instead of taking it from its cache. */
static sluice_program *warning_program(sluice_context *ctx, unsigned nonce)
{
    char src[512];
    snprintf(src, sizeof src,
             "#include \"sluice.cl\"\n"
             "#warning sluice test warning\n"
             "__kernel void quiet(SLUICE_PARAMS, global uint *x)\n"
             "{\n"
             "    SLUICE_FOR_EACH(i) x[i] = %uu;\n"
             "}\n",
             nonce);
    sluice_program *p = NULL;
    CHECK_OK(ctx, sluice_program_create_source(ctx, "quiet.cl", src, NULL, &p));
    return p;
}

/* Builds a program with a warning, with stderr captured; checks what went
 * there (`verbose`: the log, else nothing) and that the log has it. */
static void check_warning_build(int verbose, unsigned nonce)
{
    if (verbose)
        setenv("SLUICE_VERBOSE", "1", 1);
    else
        unsetenv("SLUICE_VERBOSE");
    sluice_context *ctx = check_context(0);
    sluice_program *p = warning_program(ctx, nonce);
    capture c;
    CHECK(capture_start(&c), "cannot capture stderr");
    sluice_kernel *k = NULL;
    sluice_status st = sluice_kernel_create(p, "quiet", &k);
    char *printed = capture_stop(&c);
    CHECK(st == SLUICE_OK, "build: %s", sluice_context_error(ctx));
    const char *log = sluice_program_build_log(p);
    CHECK(strstr(log, "quiet.cl:2:") && strstr(log, "sluice test warning"),
          "the build log holds the warning with its line: [%s]", log);
    CHECK(*sluice_context_error(ctx) == 0, "no error after a build with warnings: [%s]",
          sluice_context_error(ctx));
    if (verbose)
        CHECK(printed && strstr(printed, "sluice test warning"),
              "SLUICE_VERBOSE=1 prints the log: [%s]", printed ? printed : "");
    else
        CHECK(printed && printed[0] == 0, "a build that succeeds prints nothing, got [%s]",
              printed ? printed : "(capture failed)");
    free(printed);
    sluice_kernel_destroy(k);
    sluice_program_destroy(p);
    sluice_context_destroy(ctx);
    unsetenv("SLUICE_VERBOSE");
}

/* Every .cl file of the library builds without a warning and without a word
 * on stderr. */
static void check_library_kernels(const char *dir)
{
    DIR *d = opendir(dir);
    CHECK(d != NULL, "cannot open %s", dir);
    if (!d)
        return;
    sluice_context *ctx = check_context(0);
    int files = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 4 || strcmp(e->d_name + len - 3, ".cl") != 0)
            continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        sluice_program *p = NULL;
        CHECK_OK(ctx, sluice_program_create_file(ctx, path, NULL, &p));
        capture c;
        CHECK(capture_start(&c), "cannot capture stderr");
        sluice_status st = sluice_program_build(p);
        char *printed = capture_stop(&c);
        CHECK(st == SLUICE_OK, "%s: %s", e->d_name, sluice_context_error(ctx));
        CHECK(strstr(sluice_program_build_log(p), "warning") == NULL, "%s warns:\n%s", e->d_name,
              sluice_program_build_log(p));
        CHECK(printed && printed[0] == 0, "%s printed [%s]", e->d_name, printed ? printed : "");
        free(printed);
        sluice_program_destroy(p);
        files++;
    }
    closedir(d);
    CHECK(files >= 5, "only %d kernel files in %s", files, dir);
    sluice_context_destroy(ctx);
}

/* A call that succeeds after one that failed leaves no message behind. */
static void check_error_cleared(unsigned nonce)
{
    sluice_context *ctx = check_context(0);
    sluice_program *good = warning_program(ctx, nonce);
    sluice_kernel *k = NULL;

    CHECK(sluice_kernel_create(good, "no_such_kernel", &k) == SLUICE_ERROR_NOT_FOUND,
          "unknown kernel");
    CHECK(strstr(sluice_context_error(ctx), "no_such_kernel") != NULL, "message: [%s]",
          sluice_context_error(ctx));
    CHECK_OK(ctx, sluice_kernel_create(good, "quiet", &k));
    CHECK(*sluice_context_error(ctx) == 0, "after kernel_create: [%s]", sluice_context_error(ctx));

    sluice_program *bad = NULL;
    CHECK_OK(ctx, sluice_program_create_source(ctx, "bad.cl", "__kernel void f( {", NULL, &bad));
    capture c;
    CHECK(capture_start(&c), "cannot capture stderr");
    sluice_status st = sluice_program_build(bad);
    free(capture_stop(&c)); /* a failed build may print the compiler's count */
    CHECK(st == SLUICE_ERROR_BUILD && strstr(sluice_context_error(ctx), "bad.cl:1:"),
          "a build error names the line: [%s]", sluice_context_error(ctx));
    CHECK_OK(ctx, sluice_program_build(good)); /* built already */
    CHECK(*sluice_context_error(ctx) == 0, "after a build: [%s]", sluice_context_error(ctx));

    sluice_stream *s = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 16, &s));
    CHECK(sluice_stream_set_length(s, 17) == SLUICE_ERROR_OVERFLOW, "length past the capacity");
    CHECK(*sluice_context_error(ctx) != 0, "a message");
    CHECK_OK(ctx, sluice_stream_clear(s));
    CHECK(*sluice_context_error(ctx) == 0, "after stream_clear: [%s]", sluice_context_error(ctx));
    CHECK(sluice_kernel_set_arg(k, 7, 4, &nonce) == SLUICE_ERROR_INVALID_ARGUMENT, "bad index");
    CHECK_OK(ctx, sluice_kernel_set_stream(k, 0, s, 1));
    CHECK(*sluice_context_error(ctx) == 0, "after set_stream: [%s]", sluice_context_error(ctx));

    sluice_kernel_destroy(k);
    sluice_stream_destroy(s);
    sluice_program_destroy(bad);
    sluice_program_destroy(good);
    sluice_context_destroy(ctx);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_build KERNELS_DIR\n");
        return 2;
    }
    unsigned nonce = (unsigned)time(NULL) ^ ((unsigned)getpid() << 12);
    check_warning_build(0, nonce);
    check_warning_build(1, nonce + 1);
    check_error_cleared(nonce + 2);
    check_library_kernels(argv[1]);
    return check_summary();
}
