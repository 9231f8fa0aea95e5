/* Regression tests of the reliability sweep (issue 12, item 8): malformed
 * mesh and scene files that crashed, hung or took all memory in assimp or
 * in our loader, found by tools/sweep_models.py over Debian's
 * assimp-testmodels and by the libFuzzer harnesses of tests/fuzz/. Each must
 * now end in a clean error that names the file and says what is wrong, or
 * load. A crash fails the test program; a hang is cut short by alarm()
 * (SIGALRM fails it in seconds rather than at CTest's timeout). Temporary
 * files go to the working directory (the tests' build directory). */
#include "check.h"
#include "scene.h"

#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#define LEAKS_IGNORED_BEGIN() __lsan_disable()
#define LEAKS_IGNORED_END() __lsan_enable()
#else
#define LEAKS_IGNORED_BEGIN()
#define LEAKS_IGNORED_END()
#endif

/* Every load here takes milliseconds; a regressed guard hangs (assimp's PLY
 * parser) or allocates for a minute (the OFF counts) first. */
#define SECONDS_ALLOWED 60

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, n, f) != n) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(2);
    }
    fclose(f);
}

static void write_text(const char *path, const char *text)
{
    write_bytes(path, text, strlen(text));
}

/* Loads `path` as a mesh or scene; checks it fails with `want` and a
 * message holding `path` and each non-NULL `s1`, `s2`. */
static void expect_refused(const char *path, sluice_status want, const char *s1, const char *s2)
{
    char err[1024] = "";
    sr_scene *s = NULL;
    sluice_status st = sr_scene_load(path, NULL, &s, err, sizeof err);
    CHECK(st == want, "%s: %s, expected %s (%s)", path, sluice_status_string(st),
          sluice_status_string(want), err);
    CHECK(s == NULL, "%s: a scene on failure", path);
    sr_scene_destroy(s);
    const char *need[3] = {path, s1, s2};
    for (int i = 0; i < 3; ++i)
        CHECK(!need[i] || strstr(err, need[i]), "%s: message '%s' lacks '%s'", path, err, need[i]);
}

static size_t loaded_triangles(const char *path)
{
    char err[1024] = "";
    sr_scene *s = NULL;
    sluice_status st = sr_scene_load(path, NULL, &s, err, sizeof err);
    CHECK(st == SLUICE_OK, "%s: %s", path, err);
    size_t n = s ? sr_scene_triangle_count(s) : 0;
    sr_scene_destroy(s);
    return n;
}

/* assimp-testmodels' RAW/WithColor.raw: 5.2's RAW loader gives the root
 * node a NULL child, which crashed our node walk (a segmentation fault in
 * sr_scene_builder_add_mesh_file). */
static void test_raw_null_child(void)
{
    write_text("malformed_null_child.raw", "a\n0 0 0 1 0 0 0 1 0\n\nb\n0 0 1 1 0 1 0 1 1\n");
    /* the RAW loader loses the node it left out of the array: assimp's
     * leak, not ours, so LeakSanitizer ignores this one call's allocations */
    LEAKS_IGNORED_BEGIN();
    expect_refused("malformed_null_child.raw", SLUICE_ERROR_IO, "nullptr", NULL);
    LEAKS_IGNORED_END();
}

/* assimp-testmodels' invalid/OutOfMemory.off declares 353535235358
 * vertices: assimp zero-filled 16 GiB for them (over 20 s), then aborted
 * on an assertion. Here the counts wrap to 2^32 - 1 in assimp, which
 * without the guard fails with bad_alloc instead of naming the counts. */
static void test_off_counts(void)
{
    write_text("malformed_counts.off", "OFF\n4294967295 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    expect_refused("malformed_counts.off", SLUICE_ERROR_LIMIT, "OFF header", "4294967295");
    write_text("malformed_faces.off", "OFF\n3 99999 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    expect_refused("malformed_faces.off", SLUICE_ERROR_LIMIT, "OFF header", "99999");
    /* fuzz_mesh: the counts glued to the header token */
    write_text("malformed_glued.off", "OFF4444444444 1\n0 0 0\n");
    expect_refused("malformed_glued.off", SLUICE_ERROR_LIMIT, "OFF header", "4444444444");
    write_text("malformed_headless.off", "4444444444 4\n");
    expect_refused("malformed_headless.off", SLUICE_ERROR_LIMIT, "OFF header", "4444444444");
    write_text("malformed_comment.off", "333333#33 3333333333\r\r3\n");
    expect_refused("malformed_comment.off", SLUICE_ERROR_LIMIT, "count", NULL);
    write_text("fine.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    CHECK(loaded_triangles("fine.off") == 1, "a good OFF still loads");
}

/* PLY headers that made assimp 5.2's parser loop forever (no end_header
 * line; a vertical tab instead of the newline after it), read past its
 * buffer (an unknown type or format; binary data shorter than the header
 * says), or abort on its Triangulate assertion (face data missing). */
static void test_ply(void)
{
    const char *head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\n"
                       "property list uchar int vertex_indices\n";
    char text[1024];
    snprintf(text, sizeof text, "%s",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
    write_text("malformed_no_end.ply", text);
    expect_refused("malformed_no_end.ply", SLUICE_ERROR_IO, "no end_header", NULL);
    snprintf(text, sizeof text, "%send_header\v0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", head);
    write_text("malformed_vt.ply", text);
    expect_refused("malformed_vt.ply", SLUICE_ERROR_IO, "control or non-ASCII byte", NULL);
    write_text("malformed_type.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                                     "property flkat x\nend_header\n\1\2\3\4");
    expect_refused("malformed_type.ply", SLUICE_ERROR_IO, "unknown PLY property type 'flkat'",
                   NULL);
    write_text("malformed_format.ply", "ply\nformat binary_rtexle_endian 1.0\nelement vertex 1\n"
                                       "property float x\nend_header\n\1\2\3\4");
    expect_refused("malformed_format.ply", SLUICE_ERROR_IO, "format 'binary_rtexle_endian'", NULL);
    /* a binary PLY whose face list counts 200 indices that are not there */
    static const unsigned char bin_head[] = "ply\nformat binary_little_endian 1.0\n"
                                            "element vertex 3\nproperty float x\nproperty float y\n"
                                            "property float z\nelement face 1\n"
                                            "property list uchar int vertex_indices\nend_header\n";
    unsigned char bin[sizeof bin_head - 1 + 36 + 1 + 12];
    memcpy(bin, bin_head, sizeof bin_head - 1);
    memset(bin + sizeof bin_head - 1, 0, sizeof bin - (sizeof bin_head - 1));
    bin[sizeof bin_head - 1 + 36] = 200;
    write_bytes("malformed_short.ply", bin, sizeof bin);
    expect_refused("malformed_short.ply", SLUICE_ERROR_IO, "data ends within element 'face' 0",
                   NULL);
    /* fuzz_mesh: an ASCII face claiming 244444444444 corners; assimp
     * reserved room for them all */
    snprintf(text, sizeof text, "%send_header\n0 0 0\n1 0 0\n0 1 0\n244444444444 0 1 2\n", head);
    write_text("malformed_list.ply", text);
    expect_refused("malformed_list.ply", SLUICE_ERROR_LIMIT, "a list of 244444444444 items", NULL);
    /* fuzz_mesh: a NUL in ASCII data ends assimp's line there, and the
     * next "line" counted a face's corners by the billion */
    static const char nul_ply[] = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                  "element face 1\nproperty list uchar int vertex_indices\n"
                                  "end_header\n0 \0 4444444444444 0 0\n";
    write_bytes("malformed_nul.ply", nul_ply, sizeof nul_ply - 1);
    expect_refused("malformed_nul.ply", SLUICE_ERROR_IO, "is NUL", NULL);
    /* fuzz_mesh: a NUL before the magic; assimp read on, looking for
     * end_header forever */
    write_bytes("malformed_magic.ply", "\0\nply\nformat ascii 1.0 x\n", 25);
    expect_refused("malformed_magic.ply", SLUICE_ERROR_IO, "starts with \"ply\"", NULL);
    /* fuzz_mesh: digits glued before an element's name; assimp took them
     * for its count */
    write_text("malformed_name.ply", "ply\nformat ascii 1.0\nelement 88888888888888vertex 1\n"
                                     "property float x\nend_header\n0\n");
    expect_refused("malformed_name.ply", SLUICE_ERROR_IO, "is not a word", NULL);
    /* two vertex elements: assimp sized its array by the first, filled it
     * from both (a heap overflow) */
    write_text("malformed_twice.ply",
               "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
               "element vertex 3\nproperty float x\nend_header\n0\n0\n1\n2\n");
    expect_refused("malformed_twice.ply", SLUICE_ERROR_IO, "element 'vertex' declared twice", NULL);
    bin[sizeof bin_head - 1 + 36] = 3;
    bin[sizeof bin_head - 1 + 37 + 4] = 1; /* indices 0, 1, 2 */
    bin[sizeof bin_head - 1 + 37 + 8] = 2;
    float one = 1.0f;
    memcpy(bin + sizeof bin_head - 1 + 12, &one, 4); /* (1, 0, 0) */
    memcpy(bin + sizeof bin_head - 1 + 28, &one, 4); /* (0, 1, 0) */
    write_bytes("fine_binary.ply", bin, sizeof bin);
    CHECK(loaded_triangles("fine_binary.ply") == 1, "a good binary PLY still loads");
    /* a face declared, none there: assimp gave a face without indices
     * and claimed polygons, and Triangulate's assertion aborted */
    snprintf(text, sizeof text, "%send_header\n0 0 0\n1 0 0\n0 1 0\n", head);
    write_text("malformed_no_faces.ply", text);
    expect_refused("malformed_no_faces.ply", SLUICE_ERROR_IO, "face 0 has no vertices", NULL);
}

/* fuzz_mesh: a binary glTF whose JSON chunk claims 4 GiB; assimp
 * allocated it. */
static void test_glb(void)
{
    unsigned char glb[64];
    memset(glb, ' ', sizeof glb);
    memcpy(glb, "glTF\2\0\0\0\100\0\0\0\170\2\377\377JSON", 20);
    write_bytes("malformed_chunk.glb", glb, sizeof glb);
    expect_refused("malformed_chunk.glb", SLUICE_ERROR_LIMIT, "chunk longer than the file", NULL);
}

/* A file of points only: SortByPType dropped every mesh, post-processing
 * failed, and assimp's C API crashed releasing the scene. */
static void test_points_only(void)
{
    write_text("malformed_points.ply", "ply\nformat ascii 1.0\nelement vertex 2\n"
                                       "property float x\nproperty float y\nproperty float z\n"
                                       "element face 2\nproperty list uchar int vertex_indices\n"
                                       "end_header\n0 0 0\n1 0 0\n1 0\n1 1\n");
    expect_refused("malformed_points.ply", SLUICE_ERROR_IO, "no triangles or polygons", NULL);
}

/* OBJ: a NUL byte sent assimp's parser past its buffer; an MTL library
 * with a texture statement before the first newmtl made it dereference a
 * NULL material. */
static void test_obj(void)
{
    static const char nul[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\0b\nf 1 2 3\n";
    write_bytes("malformed_nul.obj", nul, sizeof nul - 1);
    expect_refused("malformed_nul.obj", SLUICE_ERROR_IO, "line 4", "NUL");
    write_text("malformed_mtl.obj", "mtllib malformed_mtl.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                    "f 1 2 3\n");
    write_text("malformed_mtl.mtl", "# a texture first\nmap_Kd x.png\nnewmtl a\n");
    expect_refused("malformed_mtl.obj", SLUICE_ERROR_IO, "malformed_mtl.mtl: line 2: 'map_Kd'",
                   NULL);
    /* the library missing: assimp falls back to the OBJ's own name */
    write_text("malformed_fallback.obj", "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                         "f 1 2 3\n");
    write_text("malformed_fallback.mtl", "bump x.png\n");
    expect_refused("malformed_fallback.obj", SLUICE_ERROR_IO, "'bump' before the first newmtl",
                   NULL);
    write_text("malformed_fallback.mtl", "# fine now\nnewmtl a\nKd 1 0 0\nmap_Kd x.png\n");
    CHECK(loaded_triangles("malformed_fallback.obj") == 1, "a good MTL still loads");
}

/* Paths that are not regular files: a directory, /dev/zero (assimp would
 * read it forever). */
static void test_not_regular(void)
{
    mkdir("malformed_dir.obj", 0755);
    expect_refused("malformed_dir.obj", SLUICE_ERROR_IO, "not a regular file", NULL);
    char err[512] = "";
    sr_scene *s = NULL;
    sluice_status st = sr_scene_load_mesh("/dev/zero", NULL, &s, err, sizeof err);
    CHECK(st == SLUICE_ERROR_IO && strstr(err, "/dev/zero: not a regular file"), "/dev/zero: %s",
          err);
    write_text("malformed_empty.stl", "");
    expect_refused("malformed_empty.stl", SLUICE_ERROR_IO, "empty", NULL);
}

/* fuzz_mesh: an STL whose only triangle is degenerate, with normals, as the
 * first mesh: the builder passed a NULL normal array to memset (UBSan). */
static void test_first_mesh_degenerate(void)
{
    sr_scene_builder *b = NULL;
    CHECK(sr_scene_builder_create("degenerate", &b) == SLUICE_OK, "create");
    uint32_t m = 0;
    sr_material mat = sr_material_make(SR_MATERIAL_DIFFUSE, "m");
    char err[512] = "";
    CHECK(sr_scene_builder_add_material(b, &mat, &m, err, sizeof err) == SLUICE_OK, "%s", err);
    const float pos[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
    const float nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    const uint32_t idx[3] = {0, 1, 2};
    sr_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.source = "collinear";
    d.positions = pos;
    d.normals = nrm;
    d.vertex_count = 3;
    d.indices = idx;
    d.triangle_count = 1;
    d.material = m;
    CHECK(sr_scene_builder_add_mesh(b, &d, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(sr_scene_builder_triangle_count(b) == 0, "the degenerate triangle is dropped");
    sr_scene_builder_destroy(b);
}

/* The memory entry point and the caller's triangle limit, which the fuzz
 * harnesses use. */
static void test_memory_and_limit(void)
{
    sr_scene_builder *b = NULL;
    CHECK(sr_scene_builder_create("mem", &b) == SLUICE_OK, "create");
    char err[512] = "";
    static const char off[] = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    sluice_status st = sr_scene_builder_add_mesh_memory(b, off, sizeof off - 1, "off", NULL, NULL,
                                                        "tiny", err, sizeof err);
    CHECK(st == SLUICE_OK && sr_scene_builder_triangle_count(b) == 1, "OFF from memory: %s", err);
    static const char obj[] = "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    st = sr_scene_builder_add_mesh_memory(b, obj, sizeof obj - 1, "obj", NULL, NULL, "mem.obj", err,
                                          sizeof err);
    CHECK(st == SLUICE_ERROR_IO && strstr(err, "mem.obj: line 1") && strstr(err, "MTL library"),
          "OBJ from memory naming an MTL: %s", err);
    sr_scene_builder_set_max_triangles(b, 10);
    const float c[3] = {0, 0, 0};
    st = sr_scene_builder_add_sphere(b, c, 1.0f, 2, 0, NULL, err, sizeof err);
    CHECK(st == SLUICE_ERROR_LIMIT && strstr(err, "limit of 10 triangles"), "limit: %s", err);
    sr_scene_builder_destroy(b);

    write_text("malformed_big.json", "{\"meshes\": [{\"shape\": \"sphere\", \"subdiv\": 64}],\n"
                                     " \"lights\": [{\"position\": [0, 3, 0], \"intensity\": 1}]}");
    sr_scene_load_options o;
    memset(&o, 0, sizeof o);
    o.max_triangles = 1000;
    sr_scene *s = NULL;
    st = sr_scene_load("malformed_big.json", &o, &s, err, sizeof err);
    CHECK(st == SLUICE_ERROR_LIMIT && s == NULL && strstr(err, "malformed_big.json"),
          "JSON scene over the caller's limit: %s", err);
    sr_scene_destroy(s);
}

int main(void)
{
    alarm(SECONDS_ALLOWED);
    test_raw_null_child();
    test_off_counts();
    test_ply();
    test_glb();
    test_points_only();
    test_obj();
    test_not_regular();
    test_first_mesh_degenerate();
    test_memory_and_limit();
    return check_summary();
}
