/* Mesh files through the public C API: the shared meshes load with the counts their README
 * gives; the same small mesh loads identically from every format; corrupted files fail with
 * an exact status and a message naming the file line; a file cut short anywhere never crashes,
 * nor does any input the fuzzers kept (tests/fuzz/regressions); .vtu written by the library
 * reads back bit for bit. Expected values come from the README, from the fixtures' hand-written
 * content (tests/data/README.md), or from an independent numpy computation over the files. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */

#include "test_support.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define SH_TEST_DATA(name) ("tests/data/" name)

/* ------------------------------------------------------------------------------------------ */
/* Temporary directory for files the tests write                                                */

static char g_dir[64];
static char g_paths[160][160]; /* every file created, removed at teardown */
static int g_path_count;

static int make_temp_dir(void** state) {
    (void)state;
    strcpy(g_dir, "/tmp/softhap_mesh_io_XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int remove_temp_dir(void** state) {
    (void)state;
    for (int i = g_path_count - 1; i >= 0; --i) remove(g_paths[i]);
    return rmdir(g_dir);
}

/* Path of name in the temporary directory, registered for removal. */
static const char* temp_path(const char* name) {
    assert_true(g_path_count < (int)(sizeof g_paths / sizeof g_paths[0]));
    char* path = g_paths[g_path_count++];
    snprintf(path, sizeof g_paths[0], "%s/%s", g_dir, name);
    return path;
}

/* Writes size bytes into path (replacing it). */
static void write_file(const char* path, const void* bytes, size_t size) {
    FILE* file = fopen(path, "wb");
    assert_non_null(file);
    assert_int_equal(fwrite(bytes, 1, size, file), size);
    assert_int_equal(fclose(file), 0);
}

/* Writes size bytes into name in the temporary directory; returns its path. */
static const char* write_temp(const char* name, const void* bytes, size_t size) {
    const char* path = temp_path(name);
    write_file(path, bytes, size);
    return path;
}

/* Reads a whole file into a malloc'ed buffer. */
static char* read_file(const char* path, size_t* size) {
    FILE* file = fopen(path, "rb");
    assert_non_null(file);
    char* bytes = NULL;
    size_t used = 0, got = 0;
    char chunk[4096];
    while ((got = fread(chunk, 1, sizeof chunk, file)) > 0) {
        bytes = realloc(bytes, used + got);
        memcpy(bytes + used, chunk, got);
        used += got;
    }
    fclose(file);
    *size = used;
    return bytes;
}

/* ------------------------------------------------------------------------------------------ */
/* Helpers                                                                                      */

/* Loads path expecting `status`; every non-NULL fragment must appear in the error message. */
static void expect_load(const char* path, sh_status status, const char* const fragments[3]) {
    sh_mesh* mesh = (sh_mesh*)&mesh; /* any non-NULL value: a failed load must reset it */
    const sh_status got = sh_mesh_load(path, &mesh);
    const char* message = sh_last_error_message();
    if (got != status) {
        print_error("%s: got %s, expected %s; message: %s\n", path, sh_status_string(got),
                    sh_status_string(status), message);
        fail();
    }
    if (status == SH_OK) {
        assert_ok(sh_mesh_destroy(mesh));
        return;
    }
    assert_null(mesh);
    for (int i = 0; i < 3 && fragments[i]; ++i)
        if (!strstr(message, fragments[i])) {
            print_error("%s: message \"%s\" lacks \"%s\"\n", path, message, fragments[i]);
            fail();
        }
}

static sh_mesh* load_ok(const char* path) {
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_load(path, &mesh));
    assert_non_null(mesh);
    return mesh;
}

/* ------------------------------------------------------------------------------------------ */
/* The shared meshes                                                                            */

typedef struct shared_mesh {
    const char* path;
    int32_t nodes, tets, orphans, reoriented, skipped; /* README (msh4_cube: counted in the file) */
    int32_t surface, edges;                           /* independent numpy count over the file */
    double volume;                                    /* independent numpy sum of |tet volume| */
} shared_mesh;

static void check_shared_mesh(const shared_mesh* expected) {
    print_message("%s\n", expected->path);
    sh_mesh* mesh = load_ok(expected->path);
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    assert_int_equal(info.node_count, expected->nodes);
    assert_int_equal(info.tet_count, expected->tets);
    assert_int_equal(info.orphan_node_count, expected->orphans);
    assert_int_equal(info.reoriented_tet_count, expected->reoriented);
    assert_int_equal(info.skipped_element_count, expected->skipped);
    assert_int_equal(info.surface_triangle_count, expected->surface);
    assert_int_equal(info.edge_count, expected->edges);
    assert_close(info.volume, expected->volume, 1e-9);
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_shared_meshes(void** state) {
    (void)state;
    static const shared_mesh meshes[] = {
        /* file                                 nodes  tets orph reor skipped  surf  edges  volume */
        {SH_TEST_MESH("liver.msh"),               181,  596,  0,  0,        0,  276,   914, 36.56085106149482},
        {SH_TEST_MESH("liver2.msh"),              507, 1493,  0,  0, 860 + 71,  860,  2429, 1.125092151433261},
        /* msh4_cube: its $Elements hold 8 points, 12 lines, 24 triangles, 24 tets; a unit cube */
        {SH_TEST_MESH("msh4_cube.msh"),            14,   24,  0,  0,  8+12+24,   24,    49, 1.0},
        /* single_tetra: (5,5,0) (0,5,0) (0,0,0) (2.5,3.5,-3), base area 12.5, height 3, listed
         * with negative orientation (by hand: det = -75) */
        {SH_TEST_MESH("single_tetra.msh"),          4,    1,  0,  1,        0,    4,     6, 12.5},
        {SH_TEST_MESH("6_tetra_bad.msh"),          17,    6,  0,  1,        0,   24,    36, 40.65},
        {SH_TEST_MESH("Armadillo_Tetra_4406.vtu"), 1446, 4406, 0,  0,        0, 2532,  7118, 231.21430723500526},
        {SH_TEST_MESH("raptorTetra_8418.vtu"),    2996, 8418,  3,  0,        0, 5750, 14284, 27.251766950557336},
        {SH_TEST_MESH("raptorTetra_19409.vtu"),   5992, 19409, 2,  0,        0, 10416, 30605, 27.489063544917354},
    };
    for (size_t i = 0; i < sizeof meshes / sizeof meshes[0]; ++i) check_shared_mesh(&meshes[i]);
}

static void test_broken_armadillo_is_refused(void** state) {
    (void)state;
    /* Header 1445 points and 4407 cells; the data has 1446 points. Line 3 holds the <Piece>. */
    const char* fragments[3] = {"Armadillo_Tetra_4406_for_test_broken.vtu:3:",
                                "header says 1445 points but the data has 1446", "header says 4407 cells"};
    expect_load(SH_TEST_MESH("Armadillo_Tetra_4406_for_test_broken.vtu"), SH_ERR_PARSE, fragments);
}

static void test_surface_obj_is_unsupported(void** state) {
    (void)state;
    const char* fragments[3] = {"liver-smooth.obj", "surface", NULL};
    expect_load(SH_TEST_MESH("liver-smooth.obj"), SH_ERR_UNSUPPORTED, fragments);
}

/* ------------------------------------------------------------------------------------------ */
/* The same mesh in every format (tests/data/README.md)                                         */

static const double kTwoTetsNodes[18] = {0.5, -1.25, 0, 1.5, -1.25, 0, 0.5, -0.25, 0,
                                         0.5, -1.25, 1, 1.5, -0.25, 1, 0.1, 0.2,   0.3};
static const int32_t kTwoTetsTets[8] = {0, 1, 2, 3, 1, 2, 3, 4};

static void check_two_tets(const char* path, int32_t skipped) {
    print_message("%s\n", path);
    sh_mesh* mesh = load_ok(path);
    const sh_mesh_info info = sh_test_mesh_info(mesh);
    assert_int_equal(info.node_count, 6);
    assert_int_equal(info.tet_count, 2);
    assert_int_equal(info.orphan_node_count, 1);
    assert_int_equal(info.reoriented_tet_count, 0);
    assert_int_equal(info.skipped_element_count, skipped);
    double nodes[18];
    int32_t tets[8];
    assert_ok(sh_mesh_get_nodes(mesh, nodes, 6));
    assert_ok(sh_mesh_get_tets(mesh, tets, 2));
    for (int i = 0; i < 18; ++i) assert_true(nodes[i] == kTwoTetsNodes[i]); /* exact: correctly rounded */
    assert_memory_equal(tets, kTwoTetsTets, sizeof tets);
    assert_close(info.volume, 0.5, 1e-15);
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_same_mesh_in_every_format(void** state) {
    (void)state;
    check_two_tets(SH_TEST_DATA("two_tets_v1.msh"), 1);   /* Gmsh 1, sparse tags, a triangle */
    check_two_tets(SH_TEST_DATA("two_tets_v22.msh"), 1);  /* Gmsh 2.2, shuffled tags, a point */
    check_two_tets(SH_TEST_DATA("two_tets_v41.msh"), 1);  /* Gmsh 4.1, two blocks, sparse tags */
    check_two_tets(SH_TEST_DATA("two_tets.vtk"), 1);      /* legacy VTK 3.0, a vertex cell */
    check_two_tets(SH_TEST_DATA("two_tets_v51.vtk"), 1);  /* legacy VTK 5.1 offsets/connectivity */
    check_two_tets(SH_TEST_DATA("two_tets.vtu"), 1);      /* VTK XML, a vertex cell */
    check_two_tets(SH_TEST_DATA("two_tets0.node"), 0);    /* TetGen from 0, given the .node */
    check_two_tets(SH_TEST_DATA("two_tets0.ele"), 0);     /* ... or the .ele */
}

static void test_same_mesh_tetgen_one_based(void** state) {
    (void)state;
    check_two_tets(SH_TEST_DATA("two_tets1.node"), 0);
    check_two_tets(SH_TEST_DATA("two_tets1.ele"), 0);
}

/* ------------------------------------------------------------------------------------------ */
/* Corrupted files: exact status, and the message names the file and line                      */

typedef struct bad_file {
    const char* name;      /* file loaded, written into the temporary directory */
    const char* content;
    const char* companion; /* TetGen: the other file of the pair, or NULL */
    const char* companion_content;
    sh_status status;
    const char* fragments[3]; /* each must appear in the message; NULL ends the list */
} bad_file;

static void check_bad_files(const bad_file* cases, size_t count) {
    for (size_t i = 0; i < count; ++i) {
        const bad_file* c = &cases[i];
        if (c->companion) write_temp(c->companion, c->companion_content, strlen(c->companion_content));
        expect_load(write_temp(c->name, c->content, strlen(c->content)), c->status, c->fragments);
    }
}

/* Gmsh 2.2, lines 1-3: format; 4-10: four nodes; 11-14: one tet. */
#define MSH2_HEAD "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
#define MSH2_NODES "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
#define MSH2_TET "$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n"
#define MSH41_HEAD "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
#define MSH1_NODES "$NOD\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$ENDNOD\n"

static void test_corrupt_gmsh(void** state) {
    (void)state;
    static const bad_file cases[] = {
        {"truncated_nodes.msh", MSH2_HEAD "$Nodes\n4\n1 0 0 0\n2 1 0 0\n", NULL, NULL, SH_ERR_PARSE,
         {"truncated_nodes.msh:7:", "after 2 of 4 nodes", NULL}},
        {"truncated_elements.msh", MSH2_HEAD MSH2_NODES "$Elements\n1\n", NULL, NULL, SH_ERR_PARSE,
         {"truncated_elements.msh:12:", "after 0 of 1 elements", NULL}},
        {"short_node.msh", MSH2_HEAD "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1\n4 0 0 1\n$EndNodes\n" MSH2_TET, NULL,
         NULL, SH_ERR_PARSE, {"short_node.msh:8:", "expected 4 fields for node", "got 3"}},
        {"unknown_tag.msh", MSH2_HEAD MSH2_NODES "$Elements\n1\n1 4 2 0 1 1 2 3 900\n$EndElements\n", NULL, NULL,
         SH_ERR_PARSE, {"unknown_tag.msh:13:", "element 1 references unknown node tag 900", NULL}},
        {"header_too_small.msh", MSH2_HEAD "$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n" MSH2_TET,
         NULL, NULL, SH_ERR_PARSE, {"header_too_small.msh:9:", "expected $EndNodes after 3 nodes", NULL}},
        {"header_too_large.msh", MSH2_HEAD "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n" MSH2_TET,
         NULL, NULL, SH_ERR_PARSE, {"header_too_large.msh:10:", "ended after 4 of the 5 nodes", NULL}},
        {"absurd_count.msh", MSH2_HEAD "$Nodes\n1000000000000\n1 0 0 0\n$EndNodes\n", NULL, NULL, SH_ERR_PARSE,
         {"absurd_count.msh:5:", "1000000000000", NULL}},
        {"huge_count.msh", MSH2_HEAD "$Nodes\n2000000000\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n", NULL,
         NULL, SH_ERR_PARSE, {"huge_count.msh:10:", "after 4 of the 2000000000 nodes", NULL}},
        {"nan_coordinate.msh", MSH2_HEAD "$Nodes\n4\n1 0 0 0\n2 nan 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n" MSH2_TET,
         NULL, NULL, SH_ERR_DEGENERATE_MESH, {"nan_coordinate.msh", "node 1 ", "non-finite"}},
        {"inf_coordinate.msh", MSH2_HEAD "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 -inf 0\n4 0 0 1\n$EndNodes\n" MSH2_TET,
         NULL, NULL, SH_ERR_DEGENERATE_MESH, {"node 2 ", "non-finite", NULL}},
        {"bad_number.msh", MSH2_HEAD "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1x\n$EndNodes\n" MSH2_TET, NULL,
         NULL, SH_ERR_PARSE, {"bad_number.msh:9:", "expected a number", "'1x'"}},
        {"duplicate_tag.msh", MSH2_HEAD "$Nodes\n4\n1 0 0 0\n2 1 0 0\n2 0 1 0\n4 0 0 1\n$EndNodes\n" MSH2_TET, NULL,
         NULL, SH_ERR_PARSE, {"duplicate_tag.msh:8:", "node tag 2 already defined on line 7", NULL}},
        {"tet_of_3_nodes.msh", MSH2_HEAD MSH2_NODES "$Elements\n1\n1 4 2 0 1 1 2 3\n$EndElements\n", NULL, NULL,
         SH_ERR_PARSE, {"tet_of_3_nodes.msh:13:", "needs 4 nodes, got 3", NULL}},
        {"flat_tet.msh", MSH2_HEAD "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 1 1 0\n$EndNodes\n" MSH2_TET, NULL,
         NULL, SH_ERR_DEGENERATE_MESH, {"flat_tet.msh", "tet 0 (line 13)", "zero volume"}},
        {"repeated_node.msh", MSH2_HEAD MSH2_NODES "$Elements\n1\n1 4 2 0 1 1 2 3 3\n$EndElements\n", NULL, NULL,
         SH_ERR_DEGENERATE_MESH, {"tet 0 (line 13)", "repeats node 2", NULL}},
        {"no_elements.msh", MSH2_HEAD MSH2_NODES, NULL, NULL, SH_ERR_PARSE, {"no_elements.msh:10:", "no element section", NULL}},
        {"binary.msh", "$MeshFormat\n2.2 1 8\n\x01\x02\x03\x04\n$EndMeshFormat\n", NULL, NULL, SH_ERR_UNSUPPORTED,
         {"binary.msh:2:", "binary", NULL}},
        {"version_4_0.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n", NULL, NULL, SH_ERR_UNSUPPORTED,
         {"version_4_0.msh:2:", "version '4'", NULL}},
        {"not_gmsh.msh", "hello world\n", NULL, NULL, SH_ERR_PARSE, {"not_gmsh.msh:1:", "expected a section", NULL}},
        {"v1_truncated.msh", MSH1_NODES "$ELM\n2\n1 4 1 1 4 1 2 3 4\n", NULL, NULL, SH_ERR_PARSE,
         {"v1_truncated.msh:10:", "after 1 of 2 elements", NULL}},
        {"v1_node_count.msh", MSH1_NODES "$ELM\n1\n1 4 1 1 5 1 2 3 4\n$ENDELM\n", NULL, NULL, SH_ERR_PARSE,
         {"v1_node_count.msh:10:", "says it has 5 nodes but the line lists 4", NULL}},
        {"v41_truncated.msh", MSH41_HEAD "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n", NULL, NULL,
         SH_ERR_PARSE, {"v41_truncated.msh:13:", "after 3 of 4 node coordinates", NULL}},
        {"v41_block_too_big.msh", MSH41_HEAD "$Nodes\n1 4 1 4\n3 1 0 5\n1\n2\n3\n4\n5\n", NULL, NULL, SH_ERR_PARSE,
         {"v41_block_too_big.msh:6:", "block of 5 nodes exceeds the 4 left", NULL}},
        {"v41_blocks_short.msh",
         MSH41_HEAD "$Nodes\n1 5 1 5\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n", NULL, NULL,
         SH_ERR_PARSE, {"v41_blocks_short.msh:14:", "the blocks hold 4 nodes but the header announces 5", NULL}},
    };
    check_bad_files(cases, sizeof cases / sizeof cases[0]);
}

/* Legacy VTK, lines 1-4: header; 5-7: four points; 8-9: one cell; 10-11: its type. */
#define VTK_HEAD "# vtk DataFile Version 3.0\nbad\nASCII\nDATASET UNSTRUCTURED_GRID\n"
#define VTK_POINTS "POINTS 4 double\n0 0 0 1 0 0\n0 1 0 0 0 1\n"
#define VTK_TET "CELLS 1 5\n4 0 1 2 3\n"
#define VTK_TYPES "CELL_TYPES 1\n10\n"

static void test_corrupt_vtk_legacy(void** state) {
    (void)state;
    static const bad_file cases[] = {
        {"truncated.vtk", VTK_HEAD "POINTS 4 double\n0 0 0 1 0 0\n", NULL, NULL, SH_ERR_PARSE,
         {"truncated.vtk:6:", "unexpected end of file", NULL}},
        {"binary.vtk", "# vtk DataFile Version 3.0\nbad\nBINARY\nDATASET UNSTRUCTURED_GRID\n", NULL, NULL,
         SH_ERR_UNSUPPORTED, {"binary.vtk:3:", "binary", NULL}},
        {"polydata.vtk", "# vtk DataFile Version 3.0\nbad\nASCII\nDATASET POLYDATA\n", NULL, NULL,
         SH_ERR_UNSUPPORTED, {"polydata.vtk:4:", "POLYDATA", NULL}},
        {"cells_size.vtk", VTK_HEAD VTK_POINTS "CELLS 1 6\n4 0 1 2 3\n" VTK_TYPES, NULL, NULL, SH_ERR_PARSE,
         {"cells_size.vtk:9:", "holds 6 values but the 1 cells hold 5", NULL}},
        {"out_of_range.vtk", VTK_HEAD VTK_POINTS "CELLS 1 5\n4 0 1 2 7\n" VTK_TYPES, NULL, NULL,
         SH_ERR_DEGENERATE_MESH, {"out_of_range.vtk", "tet 0 (line 9)", "node index 7 out of range"}},
        {"absurd_cell.vtk", VTK_HEAD VTK_POINTS "CELLS 1 5\n9223372036854775807 0 1 2 3\n" VTK_TYPES, NULL, NULL,
         SH_ERR_PARSE, {"absurd_cell.vtk:9:", "holds 5 values but cell 0 goes past it", NULL}},
        {"types_count.vtk", VTK_HEAD VTK_POINTS VTK_TET "CELL_TYPES 2\n10 10\n", NULL, NULL, SH_ERR_PARSE,
         {"types_count.vtk:10:", "2 cell types for 1 cells", NULL}},
        {"points_header_large.vtk", VTK_HEAD "POINTS 5 double\n0 0 0 1 0 0\n0 1 0 0 0 1\n" VTK_TET VTK_TYPES, NULL,
         NULL, SH_ERR_PARSE, {"points_header_large.vtk:8:", "expected a number", "'CELLS'"}},
        {"points_header_small.vtk", VTK_HEAD "POINTS 3 double\n0 0 0 1 0 0\n0 1 0 0 0 1\n" VTK_TET VTK_TYPES, NULL,
         NULL, SH_ERR_PARSE, {"points_header_small.vtk:7:", "expected POINTS, CELLS or CELL_TYPES, got '0'", NULL}},
        {"nan_point.vtk", VTK_HEAD "POINTS 4 double\n0 0 0 1 0 0\n0 NaN 0 0 0 1\n" VTK_TET VTK_TYPES, NULL, NULL,
         SH_ERR_DEGENERATE_MESH, {"node 2 ", "non-finite", NULL}},
        {"tetra_of_3.vtk", VTK_HEAD VTK_POINTS "CELLS 1 4\n3 0 1 2\n" VTK_TYPES, NULL, NULL, SH_ERR_PARSE,
         {"tetra_of_3.vtk:9:", "VTK_TETRA with 3 nodes", NULL}},
        {"no_types.vtk", VTK_HEAD VTK_POINTS VTK_TET, NULL, NULL, SH_ERR_PARSE,
         {"no_types.vtk:9:", "no CELL_TYPES section", NULL}},
        {"not_vtk.vtk", "hello\n", NULL, NULL, SH_ERR_PARSE, {"not_vtk.vtk:1:", "not a legacy VTK file", NULL}},
    };
    check_bad_files(cases, sizeof cases / sizeof cases[0]);
}

/* VTK XML, lines 1-2: root; 3: Piece; 4-9: Points (DataArray on 5); 10-20: Cells (connectivity
 * on 11-13, offsets on 14-16, types on 17-19); 21-23: closing tags. */
#define VTU_OPEN "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">\n<UnstructuredGrid>\n"
#define VTU_PIECE "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
#define VTU_POINTS_ARRAY "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n"
#define VTU_POINTS "<Points>\n" VTU_POINTS_ARRAY "0 0 0 1 0 0\n0 1 0 0 0 1\n</DataArray>\n</Points>\n"
#define VTU_CONNECTIVITY "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n"
#define VTU_OFFSETS "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n"
#define VTU_TYPES "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n10\n</DataArray>\n"
#define VTU_CELLS "<Cells>\n" VTU_CONNECTIVITY "0 1 2 3\n</DataArray>\n" VTU_OFFSETS "4\n</DataArray>\n" VTU_TYPES "</Cells>\n"
#define VTU_CLOSE "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"

static void test_corrupt_vtu(void** state) {
    (void)state;
    static const bad_file cases[] = {
        {"truncated.vtu", VTU_OPEN VTU_PIECE "<Points>\n" VTU_POINTS_ARRAY "0 0 0 1 0 0\n0 1 0 0 0 1\n", NULL, NULL,
         SH_ERR_PARSE, {"truncated.vtu:7:", "<DataArray> opened on line 5 is not closed", NULL}},
        {"binary.vtu",
         VTU_OPEN VTU_PIECE "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">\n"
                            "AAAAAAAAAAA=\n</DataArray>\n</Points>\n" VTU_CELLS VTU_CLOSE,
         NULL, NULL, SH_ERR_UNSUPPORTED, {"binary.vtu:5:", "format=\"binary\"", "ascii"}},
        {"appended.vtu",
         VTU_OPEN VTU_PIECE "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" "
                            "offset=\"0\"/>\n</Points>\n" VTU_CELLS VTU_CLOSE,
         NULL, NULL, SH_ERR_UNSUPPORTED, {"appended.vtu:5:", "appended", NULL}},
        {"point_count.vtu", VTU_OPEN "<Piece NumberOfPoints=\"5\" NumberOfCells=\"1\">\n" VTU_POINTS VTU_CELLS VTU_CLOSE,
         NULL, NULL, SH_ERR_PARSE, {"point_count.vtu:3:", "header says 5 points but the data has 4", NULL}},
        {"cell_count.vtu", VTU_OPEN "<Piece NumberOfPoints=\"4\" NumberOfCells=\"2\">\n" VTU_POINTS VTU_CELLS VTU_CLOSE,
         NULL, NULL, SH_ERR_PARSE, {"cell_count.vtu:3:", "header says 2 cells but the data has 1", NULL}},
        {"out_of_range.vtu",
         VTU_OPEN VTU_PIECE VTU_POINTS "<Cells>\n" VTU_CONNECTIVITY "0 1 2 4\n</DataArray>\n" VTU_OFFSETS
                                       "4\n</DataArray>\n" VTU_TYPES "</Cells>\n" VTU_CLOSE,
         NULL, NULL, SH_ERR_DEGENERATE_MESH, {"out_of_range.vtu", "tet 0 (line 12)", "node index 4 out of range"}},
        {"offsets_past_end.vtu",
         VTU_OPEN VTU_PIECE VTU_POINTS "<Cells>\n" VTU_CONNECTIVITY "0 1 2 3\n</DataArray>\n" VTU_OFFSETS
                                       "5\n</DataArray>\n" VTU_TYPES "</Cells>\n" VTU_CLOSE,
         NULL, NULL, SH_ERR_PARSE, {"offsets_past_end.vtu:14:", "ends at offset 5 but the connectivity holds 4", NULL}},
        {"mismatched_tag.vtu",
         VTU_OPEN VTU_PIECE "<Points>\n" VTU_POINTS_ARRAY "0 0 0 1 0 0\n0 1 0 0 0 1\n</DataArray>\n</Cells>\n", NULL,
         NULL, SH_ERR_PARSE, {"mismatched_tag.vtu:9:", "</Cells> does not close <Points> opened on line 4", NULL}},
        {"bad_number.vtu",
         VTU_OPEN VTU_PIECE "<Points>\n" VTU_POINTS_ARRAY "0 0 0 1 0 0\n0 1 0 0 0 x\n</DataArray>\n</Points>\n" VTU_CELLS
             VTU_CLOSE,
         NULL, NULL, SH_ERR_PARSE, {"bad_number.vtu:7:", "expected a number", "'x'"}},
        {"nan_point.vtu",
         VTU_OPEN VTU_PIECE "<Points>\n" VTU_POINTS_ARRAY "0 0 0 1 0 0\nnan 1 0 0 0 1\n</DataArray>\n</Points>\n" VTU_CELLS
             VTU_CLOSE,
         NULL, NULL, SH_ERR_DEGENERATE_MESH, {"node 2 ", "non-finite", NULL}},
        {"no_types.vtu",
         VTU_OPEN VTU_PIECE VTU_POINTS "<Cells>\n" VTU_CONNECTIVITY "0 1 2 3\n</DataArray>\n" VTU_OFFSETS
                                       "4\n</DataArray>\n</Cells>\n" VTU_CLOSE,
         NULL, NULL, SH_ERR_PARSE, {"no_types.vtu", "no 'types' DataArray", NULL}},
        {"polydata.vtu", "<VTKFile type=\"PolyData\" version=\"0.1\">\n</VTKFile>\n", NULL, NULL, SH_ERR_UNSUPPORTED,
         {"polydata.vtu:1:", "PolyData", NULL}},
        {"not_xml.vtu", "hello\n", NULL, NULL, SH_ERR_PARSE, {"not_xml.vtu:1:", "not a VTK XML file", NULL}},
    };
    check_bad_files(cases, sizeof cases / sizeof cases[0]);
}

#define TG_NODE "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n"
#define TG_NODE_1 "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
#define TG_ELE "1 4 0\n0 0 1 2 3\n"

static void test_corrupt_tetgen(void** state) {
    (void)state;
    static const bad_file cases[] = {
        {"truncated.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n", "truncated.ele", TG_ELE, SH_ERR_PARSE,
         {"truncated.node:3:", "after 2 of the 4 nodes", NULL}},
        {"truncated_ele.ele", "2 4 0\n0 0 1 2 3\n", "truncated_ele.node", TG_NODE, SH_ERR_PARSE,
         {"truncated_ele.ele:2:", "after 1 of the 2 tets", NULL}},
        {"missing_ele.node", TG_NODE, NULL, NULL, SH_ERR_IO, {"missing_ele.ele", NULL, NULL}},
        {"missing_node.ele", TG_ELE, NULL, NULL, SH_ERR_IO, {"missing_node.node", NULL, NULL}},
        {"out_of_range.ele", "1 4 0\n0 0 1 2 4\n", "out_of_range.node", TG_NODE, SH_ERR_DEGENERATE_MESH,
         {"tet 0 (line 2)", "node index 4 out of range", NULL}},
        {"one_based_zero.ele", "1 4 0\n1 0 1 2 3\n", "one_based_zero.node", TG_NODE_1, SH_ERR_DEGENERATE_MESH,
         {"tet 0 (line 2)", "node index -1 out of range", NULL}},
        {"first_index_2.node", "4 3 0 0\n2 0 0 0\n3 1 0 0\n4 0 1 0\n5 0 0 1\n", "first_index_2.ele", TG_ELE,
         SH_ERR_PARSE, {"first_index_2.node:2:", "must be 0 or 1", NULL}},
        {"sequence.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n3 0 1 0\n2 0 0 1\n", "sequence.ele", TG_ELE, SH_ERR_PARSE,
         {"sequence.node:4:", "node index 3 out of sequence, expected 2", NULL}},
        {"fields.ele", "1 4 0\n0 0 1 2\n", "fields.node", TG_NODE, SH_ERR_PARSE,
         {"fields.ele:2:", "expected 5 fields", "got 4"}},
        {"extra.node", "3 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n", "extra.ele", TG_ELE, SH_ERR_PARSE,
         {"extra.node:5:", "more lines than the 3 nodes", NULL}},
        {"planar.node", "4 2 0 0\n0 0 0\n1 1 0\n2 0 1\n3 1 1\n", "planar.ele", TG_ELE, SH_ERR_UNSUPPORTED,
         {"planar.node:1:", "dimension 2", NULL}},
        {"nan.node", "4 3 0 0\n0 0 0 0\n1 nan 0 0\n2 0 1 0\n3 0 0 1\n", "nan.ele", TG_ELE, SH_ERR_DEGENERATE_MESH,
         {"node 1 ", "non-finite", NULL}},
    };
    check_bad_files(cases, sizeof cases / sizeof cases[0]);
}

/* Random bytes (a fixed linear congruential sequence, NULs included) under every extension,
 * alone and after a valid start: refused as malformed, never a crash or a hang. */
static void test_binary_garbage(void** state) {
    (void)state;
    unsigned char garbage[4096];
    uint32_t x = 12345u;
    for (size_t i = 0; i < sizeof garbage; ++i) {
        x = x * 1664525u + 1013904223u;
        garbage[i] = (unsigned char)(x >> 24);
    }
    const char* const names[] = {"garbage.msh", "garbage.vtu", "garbage.vtk", "garbage.node"};
    const char* const none[3] = {NULL, NULL, NULL};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        expect_load(write_temp(names[i], garbage, sizeof garbage), SH_ERR_PARSE, none);
    write_temp("garbage_ele.node", TG_NODE, strlen(TG_NODE));
    expect_load(write_temp("garbage_ele.ele", garbage, sizeof garbage), SH_ERR_PARSE, none);

    /* A valid beginning, then garbage where the data should be. */
    static const char* const starts[][2] = {
        {"garbage_nodes.msh", MSH2_HEAD "$Nodes\n4\n"},
        {"garbage_points.vtk", VTK_HEAD "POINTS 4 double\n"},
        {"garbage_points.vtu", VTU_OPEN VTU_PIECE "<Points>\n" VTU_POINTS_ARRAY},
        {"garbage_nodes.node", "4 3 0 0\n"},
    };
    for (size_t i = 0; i < sizeof starts / sizeof starts[0]; ++i) {
        char content[sizeof garbage + 512];
        const size_t n = strlen(starts[i][1]);
        memcpy(content, starts[i][1], n);
        memcpy(content + n, garbage, sizeof garbage);
        expect_load(write_temp(starts[i][0], content, n + sizeof garbage), SH_ERR_PARSE, none);
    }
}

/* Loads path, which must load or be refused as malformed, unsupported or degenerate with the
 * file (name) named in the message: never a crash, a hang, an I/O or internal error. what names
 * the input in a failure report. */
static void expect_clean_load(const char* path, const char* name, const char* what) {
    sh_mesh* mesh = NULL;
    const sh_status status = sh_mesh_load(path, &mesh);
    if (status == SH_OK) {
        assert_ok(sh_mesh_destroy(mesh));
        return;
    }
    if ((status != SH_ERR_PARSE && status != SH_ERR_UNSUPPORTED && status != SH_ERR_DEGENERATE_MESH) ||
        !strstr(sh_last_error_message(), name)) {
        print_error("%s: %s (%s)\n", what, sh_status_string(status), sh_last_error_message());
        fail();
    }
}

/* Every proper prefix of a fixture (a file cut short anywhere) loads or is refused cleanly
 * (expect_clean_load). A TetGen prefix is loaded with the other file of its pair complete. */
static void check_prefixes(const char* fixture, const char* name, const char* companion_fixture,
                           const char* companion_name) {
    print_message("%s\n", fixture);
    if (companion_fixture) {
        size_t size = 0;
        char* bytes = read_file(companion_fixture, &size);
        write_temp(companion_name, bytes, size);
        free(bytes);
    }
    size_t size = 0;
    char* bytes = read_file(fixture, &size);
    const char* path = temp_path(name);
    for (size_t length = 0; length < size; ++length) {
        write_file(path, bytes, length);
        char what[256];
        snprintf(what, sizeof what, "%s cut to %zu bytes", fixture, length);
        expect_clean_load(path, name, what);
    }
    free(bytes);
}

static void test_every_truncation_fails_cleanly(void** state) {
    (void)state;
    check_prefixes(SH_TEST_DATA("two_tets_v1.msh"), "cut_v1.msh", NULL, NULL);
    check_prefixes(SH_TEST_DATA("two_tets_v22.msh"), "cut_v22.msh", NULL, NULL);
    check_prefixes(SH_TEST_DATA("two_tets_v41.msh"), "cut_v41.msh", NULL, NULL);
    check_prefixes(SH_TEST_DATA("two_tets.vtk"), "cut.vtk", NULL, NULL);
    check_prefixes(SH_TEST_DATA("two_tets_v51.vtk"), "cut_v51.vtk", NULL, NULL);
    check_prefixes(SH_TEST_DATA("two_tets.vtu"), "cut.vtu", NULL, NULL);
    check_prefixes(SH_TEST_DATA("two_tets0.node"), "cut_node.node", SH_TEST_DATA("two_tets0.ele"), "cut_node.ele");
    check_prefixes(SH_TEST_DATA("two_tets0.ele"), "cut_ele.ele", SH_TEST_DATA("two_tets0.node"), "cut_ele.node");
}

/* ------------------------------------------------------------------------------------------ */
/* Fuzzer findings: inputs of the fuzz targets kept in tests/fuzz/regressions/<format>/, written */
/* as their target writes them (tests/fuzz/README.md)                                           */

#define SH_TEST_REGRESSIONS "tests/fuzz/regressions/"

/* The text target's input is one field of a Gmsh 2.2 file: the tag, or the x, of a fifth node
 * (line 10) that no tet uses. */
#define FIELD_NODES MSH2_HEAD "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
#define FIELD_REST " 0 0\n$EndNodes\n" MSH2_TET

/* Writes prefix, then bytes[0, size), then suffix into path. */
static void write_between(const char* path, const char* prefix, const char* bytes, size_t size, const char* suffix) {
    const size_t before = strlen(prefix), after = strlen(suffix);
    char* content = malloc(before + size + after);
    assert_non_null(content);
    memcpy(content, prefix, before);
    if (size > 0) memcpy(content + before, bytes, size);
    memcpy(content + before + size, suffix, after);
    write_file(path, content, before + size + after);
    free(content);
}

/* Temporary paths the regressions are written to, registered once. */
typedef struct regression_paths {
    const char* by_extension[3]; /* msh, vtk, vtu */
    const char* node;
    const char* ele;
    const char* tag;
    const char* x;
} regression_paths;

static regression_paths make_regression_paths(void) {
    const regression_paths paths = {{temp_path("regression.msh"), temp_path("regression.vtk"), temp_path("regression.vtu")},
                                    temp_path("regression.node"), temp_path("regression.ele"),
                                    temp_path("regression_tag.msh"), temp_path("regression_x.msh")};
    return paths;
}

/* Loads the regression input bytes of format as its fuzz target does; what names it in failures. */
static void load_regression(const regression_paths* paths, const char* format, const char* bytes, size_t size,
                            const char* what) {
    static const char* const extensions[3] = {"gmsh", "vtk", "vtu"};
    for (int i = 0; i < 3; ++i)
        if (strcmp(format, extensions[i]) == 0) {
            write_file(paths->by_extension[i], bytes, size);
            expect_clean_load(paths->by_extension[i], "regression.", what);
            return;
        }
    if (strcmp(format, "text") == 0) {
        write_between(paths->tag, FIELD_NODES, bytes, size, " 0.5" FIELD_REST);
        expect_clean_load(paths->tag, "regression_tag.msh", what);
        write_between(paths->x, FIELD_NODES "5 ", bytes, size, FIELD_REST);
        expect_clean_load(paths->x, "regression_x.msh", what);
        return;
    }
    assert_string_equal(format, "tetgen"); /* the .node text, a line ".ele", the .ele text */
    size_t split = 0;
    while (split + 6 <= size && memcmp(bytes + split, "\n.ele\n", 6) != 0) ++split;
    const int found = split + 6 <= size;
    const size_t ele = found ? split + 6 : size;
    write_file(paths->node, bytes, found ? split : size);
    write_file(paths->ele, bytes + ele, size - ele);
    expect_clean_load(paths->node, "regression.", what);
    expect_clean_load(paths->ele, "regression.", what);
}

/* Every regression input loads or is refused cleanly (expect_clean_load), as the fuzzers demand. */
static void test_fuzz_regressions_load_cleanly(void** state) {
    (void)state;
    static const char* const formats[] = {"gmsh", "vtk", "vtu", "tetgen", "text"};
    const regression_paths paths = make_regression_paths();
    int count = 0;
    for (size_t f = 0; f < sizeof formats / sizeof formats[0]; ++f) {
        char folder[128];
        snprintf(folder, sizeof folder, SH_TEST_REGRESSIONS "%s", formats[f]);
        DIR* dir = opendir(folder);
        if (!dir) continue; /* no finding in this format */
        for (struct dirent* entry = readdir(dir); entry; entry = readdir(dir)) {
            if (entry->d_name[0] == '.') continue;
            char path[512];
            snprintf(path, sizeof path, "%s/%s", folder, entry->d_name);
            print_message("%s\n", path);
            size_t size = 0;
            char* bytes = read_file(path, &size);
            load_regression(&paths, formats[f], bytes, size, path);
            free(bytes);
            ++count;
        }
        closedir(dir);
    }
    assert_true(count > 0);
}

/* text/plus_minus_sign.txt: "+-1" was read as -1 (the '+' was dropped, then std::from_chars took
 * the '-' as the sign). It is no number: refused naming the line and the field. A lone leading
 * '+' still reads. */
static void test_fuzz_plus_minus_sign_is_no_number(void** state) {
    (void)state;
    size_t size = 0;
    char* field = read_file(SH_TEST_REGRESSIONS "text/plus_minus_sign.txt", &size);
    const char* tag = temp_path("plus_minus_tag.msh");
    write_between(tag, FIELD_NODES, field, size, " 0.5" FIELD_REST);
    const char* const as_tag[3] = {"plus_minus_tag.msh:10:", "expected an integer for a node tag, got '+-1'", NULL};
    expect_load(tag, SH_ERR_PARSE, as_tag);
    const char* x = temp_path("plus_minus_x.msh");
    write_between(x, FIELD_NODES "5 ", field, size, FIELD_REST);
    const char* const as_x[3] = {"plus_minus_x.msh:10:", "expected a number for a node coordinate, got '+-1'", NULL};
    expect_load(x, SH_ERR_PARSE, as_x);
    free(field);

    const char* plus = temp_path("plus.msh");
    write_between(plus, FIELD_NODES "+5 ", "+0.25", 5, FIELD_REST);
    sh_mesh* mesh = load_ok(plus);
    double nodes[15];
    assert_ok(sh_mesh_get_nodes(mesh, nodes, 5));
    assert_true(nodes[12] == 0.25);
    assert_ok(sh_mesh_destroy(mesh));
}

static void test_empty_files(void** state) {
    (void)state;
    const char* const names[] = {"empty.msh", "empty.vtk", "empty.vtu", "empty.node", "empty.ele"};
    const char* const fragments[3] = {":1:", "empty", NULL};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        expect_load(write_temp(names[i], "", 0), SH_ERR_PARSE, fragments);
    expect_load(write_temp("blank.msh", " \n\n \t\n", 6), SH_ERR_PARSE, fragments);
}

static void test_missing_unknown_and_bad_arguments(void** state) {
    (void)state;
    const char* const missing[3] = {"does_not_exist.msh", NULL, NULL};
    expect_load(SH_TEST_DATA("does_not_exist.msh"), SH_ERR_IO, missing);

    const char* const directory[3] = {"directory.msh", NULL, NULL};
    const char* dir = temp_path("directory.msh");
    assert_int_equal(mkdir(dir, 0700), 0);
    expect_load(dir, SH_ERR_IO, directory);

    const char* const unknown[3] = {"unknown.xyz", "'xyz'", NULL};
    expect_load(write_temp("unknown.xyz", "1 2 3\n", 6), SH_ERR_UNSUPPORTED, unknown);
    const char* const no_extension[3] = {"no_extension", NULL, NULL};
    expect_load(write_temp("no_extension", "1 2 3\n", 6), SH_ERR_UNSUPPORTED, no_extension);

    sh_mesh* mesh = NULL;
    assert_status(sh_mesh_load(NULL, &mesh), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_mesh_load(SH_TEST_MESH("liver.msh"), NULL), SH_ERR_INVALID_ARGUMENT);
}

/* ------------------------------------------------------------------------------------------ */
/* Writing .vtu                                                                                 */

/* Asserts that b has a's nodes (bitwise) and tets. */
static void assert_same_mesh(const sh_mesh* a, const sh_mesh* b) {
    const sh_mesh_info ia = sh_test_mesh_info(a), ib = sh_test_mesh_info(b);
    assert_int_equal(ib.node_count, ia.node_count);
    assert_int_equal(ib.tet_count, ia.tet_count);
    assert_int_equal(ib.orphan_node_count, ia.orphan_node_count);
    const size_t node_values = 3 * (size_t)ia.node_count, tet_values = 4 * (size_t)ia.tet_count;
    double* nodes_a = malloc(sizeof(double) * node_values);
    double* nodes_b = malloc(sizeof(double) * node_values);
    int32_t* tets_a = malloc(sizeof(int32_t) * tet_values);
    int32_t* tets_b = malloc(sizeof(int32_t) * tet_values);
    assert_ok(sh_mesh_get_nodes(a, nodes_a, ia.node_count));
    assert_ok(sh_mesh_get_nodes(b, nodes_b, ia.node_count));
    assert_ok(sh_mesh_get_tets(a, tets_a, ia.tet_count));
    assert_ok(sh_mesh_get_tets(b, tets_b, ia.tet_count));
    assert_memory_equal(nodes_a, nodes_b, sizeof(double) * node_values);
    assert_memory_equal(tets_a, tets_b, sizeof(int32_t) * tet_values);
    free(nodes_a);
    free(nodes_b);
    free(tets_a);
    free(tets_b);
}

/* Writes mesh with sh_mesh_write_vtu and loads the file back: the same nodes and tets. */
static void check_round_trip(const sh_mesh* mesh, const char* name) {
    const char* path = temp_path(name);
    assert_ok(sh_mesh_write_vtu(mesh, path));
    sh_mesh* back = load_ok(path);
    assert_same_mesh(mesh, back);
    assert_int_equal(sh_test_mesh_info(back).reoriented_tet_count, 0); /* written already positively oriented */
    assert_ok(sh_mesh_destroy(back));
}

static void test_vtu_round_trip_shared_meshes(void** state) {
    (void)state;
    sh_mesh* liver = load_ok(SH_TEST_MESH("liver.msh"));
    check_round_trip(liver, "liver.vtu");
    assert_ok(sh_mesh_destroy(liver));
    sh_mesh* raptor = load_ok(SH_TEST_MESH("raptorTetra_8418.vtu"));
    check_round_trip(raptor, "raptor.vtu");
    assert_ok(sh_mesh_destroy(raptor));
}

static void test_vtu_round_trip_awkward_doubles(void** state) {
    (void)state;
    /* A unit tet, then orphan nodes holding values that need all 17 digits, signed zero,
     * subnormals and the largest double. */
    const double nodes[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,
                            0.1, 1.0 / 3.0, -0.0,
                            1e-300, 4.9406564584124654e-324, 1.7976931348623157e308,
                            -2.5e-17, 123456789.12345679, 2.2250738585072014e-308};
    const int32_t tets[] = {0, 1, 2, 3};
    sh_mesh* mesh = NULL;
    assert_ok(sh_mesh_create(nodes, 7, tets, 1, &mesh));
    check_round_trip(mesh, "awkward.vtu");
    assert_ok(sh_mesh_destroy(mesh));
}

/* Bodies write through the same writer: an FEM body's tets with a "velocity" point array (which
 * the loader passes over), a spring body's springs as VTK_LINE cells (which it skips). */
static void test_body_vtu_files(void** state) {
    (void)state;
    sh_world* world = sh_test_world(0.0);

    sh_mesh* liver = load_ok(SH_TEST_MESH("liver.msh"));
    sh_fem_body_def fem;
    sh_fem_body_def_default(&fem);
    fem.mesh = liver;
    sh_body_id organ = SH_NULL_ID;
    assert_ok(sh_fem_body_create(world, &fem, &organ));
    const char* organ_path = temp_path("organ.vtu");
    assert_ok(sh_body_write_vtu(world, organ, organ_path));
    size_t size = 0;
    char* text = read_file(organ_path, &size);
    text = realloc(text, size + 1);
    text[size] = '\0';
    assert_non_null(strstr(text, "<PointData Vectors=\"velocity\">"));
    free(text);
    sh_mesh* written = load_ok(organ_path);
    assert_same_mesh(liver, written); /* a body at rest is its mesh */
    assert_ok(sh_mesh_destroy(written));
    assert_ok(sh_mesh_destroy(liver));

    sh_spring_body_def spring;
    sh_spring_body_def_default(&spring); /* only for its default spring law */
    const sh_body_id pair = sh_test_spring_pair(world, 0.01, &spring.params, 0.001, SH_INTEGRATOR_SYMPLECTIC_EULER,
                                                SH_UNSTABLE_SUBSTEP);
    const char* pair_path = temp_path("pair.vtu");
    assert_ok(sh_body_write_vtu(world, pair, pair_path));
    const char* const no_tets[3] = {"pair.vtu", "no tetrahedra", NULL};
    expect_load(pair_path, SH_ERR_DEGENERATE_MESH, no_tets);
    assert_ok(sh_world_destroy(world));
}

static void test_vtu_write_errors(void** state) {
    (void)state;
    sh_mesh* mesh = sh_test_unit_tet(1.0);
    assert_status(sh_mesh_write_vtu(mesh, "/nonexistent-softhap-dir/out.vtu"), SH_ERR_IO);
    assert_non_null(strstr(sh_last_error_message(), "/nonexistent-softhap-dir/out.vtu"));
    assert_status(sh_mesh_write_vtu(mesh, NULL), SH_ERR_INVALID_ARGUMENT);
    assert_status(sh_mesh_write_vtu(NULL, temp_path("null.vtu")), SH_ERR_INVALID_HANDLE);
    assert_ok(sh_mesh_destroy(mesh));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shared_meshes),
        cmocka_unit_test(test_broken_armadillo_is_refused),
        cmocka_unit_test(test_surface_obj_is_unsupported),
        cmocka_unit_test(test_same_mesh_in_every_format),
        cmocka_unit_test(test_same_mesh_tetgen_one_based),
        cmocka_unit_test(test_corrupt_gmsh),
        cmocka_unit_test(test_corrupt_vtk_legacy),
        cmocka_unit_test(test_corrupt_vtu),
        cmocka_unit_test(test_corrupt_tetgen),
        cmocka_unit_test(test_binary_garbage),
        cmocka_unit_test(test_every_truncation_fails_cleanly),
        cmocka_unit_test(test_fuzz_regressions_load_cleanly),
        cmocka_unit_test(test_fuzz_plus_minus_sign_is_no_number),
        cmocka_unit_test(test_empty_files),
        cmocka_unit_test(test_missing_unknown_and_bad_arguments),
        cmocka_unit_test(test_vtu_round_trip_shared_meshes),
        cmocka_unit_test(test_vtu_round_trip_awkward_doubles),
        cmocka_unit_test(test_body_vtu_files),
        cmocka_unit_test(test_vtu_write_errors),
    };
    return cmocka_run_group_tests(tests, make_temp_dir, remove_temp_dir);
}
