/*
 * carve.c: a simulator's carving loop against organtex's C API.
 *
 *   carve BAKE_DIR OUT.glb
 *
 * Opens the default bake (`organtex bake scenes/hysteroscopy_myomas.toml`),
 * takes node "uterus" (its wall, 254k tets, a lapped solid texture), and
 * drives a burr of radius 1.5 mm along a tunnel through the wall in 100
 * steps, as a simulator's tool would between frames. After each step it
 * checks what the runtime promises:
 *  - the carved surface is closed and consistently oriented: every edge
 *    the step touched has one face each way (the stuffed wall's own
 *    boundary has an edge or two with two faces each way; those may stay);
 *  - every new face's atlas texel at its centroid holds the interior's
 *    colour there (organtex_node_colours) within 1/255;
 *  - the step's time, for the median and worst printed at the end.
 * Then it feeds bad input (ids out of range or removed twice, NaN, a NULL
 * handle, a zero radius, a missing node, a folder that is not a bake) and
 * checks each gets its status and message while the session goes on, and
 * writes the carved surface with its atlas as OUT.glb.
 *
 * Exit status 0 when every check holds. ctest runs it (CMakeLists.txt).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "organtex.h"

#define STEPS 100
#define RADIUS 1.5

static int failures = 0;

#define CHECK(cond, ...)                                  \
    do {                                                  \
        if (!(cond)) {                                    \
            fprintf(stderr, "carve: check failed: ");     \
            fprintf(stderr, __VA_ARGS__);                 \
            fprintf(stderr, "\n");                        \
            if (++failures > 20) exit(1);                 \
        }                                                 \
    } while (0)

/* A call that must succeed. */
static void must(organtex_status s, const char *what) {
    if (s != ORGANTEX_OK) {
        fprintf(stderr, "carve: %s failed: %s: %s\n", what, organtex_status_name(s), organtex_last_error());
        exit(1);
    }
}

/* The tunnel: round the wall's middle at z = 20 (an ellipse of semi-axes
 * 18.5 and 11.8 mm), 95% of the way round in STEPS steps. */
static void wall_path(int step, double p[3]) {
    double a = (double)step / STEPS * 0.95 * 6.283185307179586;
    p[0] = 18.5 * cos(a);
    p[1] = 11.8 * sin(a);
    p[2] = 20.0;
}

/* Directed edges of the surface and how many faces use each: an open
 * addressing table keyed by (from << 32 | to). */
typedef struct {
    uint64_t *keys;
    int32_t *counts;
    uint8_t *defect; /* used twice before carving */
    size_t mask;
} Edges;

static size_t slot(Edges *e, uint32_t a, uint32_t b) {
    uint64_t key = ((uint64_t)a << 32 | b) + 1; /* 0 marks an empty slot */
    size_t i = (size_t)(key * 0x9E3779B97F4A7C15ull) & e->mask;
    while (e->keys[i] != 0 && e->keys[i] != key) i = (i + 1) & e->mask;
    e->keys[i] = key;
    return i;
}

static void add_face(Edges *e, const uint32_t v[3], int by) {
    for (int k = 0; k < 3; ++k) e->counts[slot(e, v[k], v[(k + 1) % 3])] += by;
}

/* Each edge of face v: one face each way (or, for the wall's own defects,
 * as many each way as before carving). */
static void check_face_edges(Edges *e, const uint32_t v[3], int step) {
    for (int k = 0; k < 3; ++k) {
        uint32_t a = v[k], b = v[(k + 1) % 3];
        size_t ab = slot(e, a, b), ba = slot(e, b, a);
        int32_t most = e->defect[ab] ? 2 : 1;
        CHECK(e->counts[ab] == e->counts[ba], "step %d: edge %u-%u has %d faces one way, %d the other", step, a, b,
              e->counts[ab], e->counts[ba]);
        CHECK(e->counts[ab] <= most, "step %d: edge %u->%u has %d faces", step, a, b, e->counts[ab]);
    }
}

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The texel at a face's centroid against the interior's colour there,
 * a hair inside the face's own tet (the removed one across is gone). */
static int check_texel(const organtex_node *node, organtex_carving *carving, const organtex_tet_mesh *mesh,
                       const organtex_face *f, int step) {
    const uint8_t *rgba;
    uint32_t side;
    must(organtex_carving_page(carving, f->page, &rgba, &side), "organtex_carving_page");
    double u = (f->uvs[0] + f->uvs[2] + f->uvs[4]) / 3.0 * side;
    double v = (f->uvs[1] + f->uvs[3] + f->uvs[5]) / 3.0 * side;
    long tx = (long)floor(u), ty = (long)floor(v);
    /* The texel centre's barycentric coordinates in the face's chart. */
    double cx = tx + 0.5, cy = ty + 0.5;
    double x0 = f->uvs[0] * side, y0 = f->uvs[1] * side, x1 = f->uvs[2] * side, y1 = f->uvs[3] * side,
           x2 = f->uvs[4] * side, y2 = f->uvs[5] * side;
    double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    if (fabs(area) < 1e-12) return 0;
    double w1 = ((cx - x0) * (y2 - y0) - (x2 - x0) * (cy - y0)) / area;
    double w2 = ((x1 - x0) * (cy - y0) - (cx - x0) * (y1 - y0)) / area;
    double w0 = 1.0 - w1 - w2;
    if (w0 < 0 || w1 < 0 || w2 < 0) return 0; /* a thin face: its centroid's texel is off it */
    uint32_t tet = f->id / 4;
    double centroid[3] = {0, 0, 0}, point[3];
    for (int c = 0; c < 4; ++c)
        for (int a = 0; a < 3; ++a) centroid[a] += mesh->positions[3 * mesh->tets[4 * tet + c] + a] / 4.0;
    for (int a = 0; a < 3; ++a) {
        double p = w0 * mesh->positions[3 * f->vertices[0] + a] + w1 * mesh->positions[3 * f->vertices[1] + a] +
                   w2 * mesh->positions[3 * f->vertices[2] + a];
        point[a] = p + (centroid[a] - p) * 1e-7;
    }
    uint8_t want[3];
    must(organtex_node_colours(node, point, 1, want), "organtex_node_colours");
    const uint8_t *got = rgba + 4 * ((size_t)ty * side + (size_t)tx);
    for (int k = 0; k < 3; ++k)
        CHECK(abs((int)got[k] - (int)want[k]) <= 1, "step %d: face %u's texel is %u,%u,%u, the interior %u,%u,%u",
              step, f->id, got[0], got[1], got[2], want[0], want[1], want[2]);
    CHECK(got[3] == 255, "step %d: face %u's texel is not opaque", step, f->id);
    return 1;
}

/* A call that must fail with `want`, leaving a message. */
static void refused(organtex_status s, organtex_status want, const char *what) {
    CHECK(s == want, "%s: got %s, expected %s", what, organtex_status_name(s), organtex_status_name(want));
    CHECK(strlen(organtex_last_error()) > 0, "%s: no message", what);
    printf("  refused %-28s %s\n", what, organtex_last_error());
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: carve BAKE_DIR OUT.glb\n");
        return 2;
    }
    CHECK(organtex_abi_version() == ORGANTEX_ABI_VERSION, "library ABI %u, header %u", organtex_abi_version(),
          ORGANTEX_ABI_VERSION);
    CHECK(strcmp(organtex_version(), ORGANTEX_VERSION) == 0, "library %s, header %s", organtex_version(),
          ORGANTEX_VERSION);

    organtex_bake *bake = NULL;
    must(organtex_bake_open(argv[1], &bake), "organtex_bake_open");
    size_t nodes = 0;
    must(organtex_bake_node_count(bake, &nodes), "organtex_bake_node_count");
    const char *first = NULL;
    must(organtex_bake_node_name(bake, 0, &first), "organtex_bake_node_name");
    printf("organtex %s: bake %s, %zu node(s), first '%s'\n", organtex_version(), argv[1], nodes, first);
    organtex_node *node = NULL;
    must(organtex_bake_node(bake, "uterus", &node), "organtex_bake_node");
    organtex_tet_mesh mesh;
    must(organtex_node_tet_mesh(node, &mesh), "organtex_node_tet_mesh");
    const uint32_t *faces, *ids;
    size_t boundary;
    must(organtex_node_boundary(node, &faces, &ids, &boundary), "organtex_node_boundary");
    printf("uterus: %zu vertices, %zu tets, %zu boundary faces\n", mesh.vertex_count, mesh.tet_count, boundary);

    Edges edges;
    edges.mask = (1u << 19) - 1;
    edges.keys = calloc(edges.mask + 1, sizeof *edges.keys);
    edges.counts = calloc(edges.mask + 1, sizeof *edges.counts);
    edges.defect = calloc(edges.mask + 1, 1);
    for (size_t f = 0; f < boundary; ++f) add_face(&edges, faces + 3 * f, 1);
    size_t defects = 0;
    for (size_t i = 0; i <= edges.mask; ++i)
        if (edges.keys[i] && edges.counts[i] > 1) edges.defect[i] = 1, ++defects;
    printf("the wall's own boundary: %zu directed edges with two faces\n", defects);

    organtex_carving_options options = organtex_carving_options_default();
    organtex_carving *carving = NULL;
    must(organtex_carving_new(node, &options, &carving), "organtex_carving_new");

    double seconds[STEPS];
    size_t removed = 0, appeared = 0, texels_checked = 0;
    double a[3], b[3];
    wall_path(0, a);
    for (int i = 1; i <= STEPS; ++i) {
        wall_path(i, b);
        organtex_step step;
        must(organtex_carving_capsule(carving, a, b, RADIUS, &step), "organtex_carving_capsule");
        memcpy(a, b, sizeof a);
        seconds[i - 1] = step.seconds;
        removed += step.removed_count;
        appeared += step.appeared_count;
        for (size_t k = 0; k < step.vanished_count; ++k) add_face(&edges, step.vanished[k].vertices, -1);
        for (size_t k = 0; k < step.appeared_count; ++k) add_face(&edges, step.appeared[k].vertices, 1);
        for (size_t k = 0; k < step.vanished_count; ++k) check_face_edges(&edges, step.vanished[k].vertices, i);
        for (size_t k = 0; k < step.appeared_count; ++k) {
            check_face_edges(&edges, step.appeared[k].vertices, i);
            texels_checked += check_texel(node, carving, &mesh, &step.appeared[k], i);
        }
        CHECK(step.dirty_count > 0 || step.appeared_count == 0, "step %d: new faces but no dirty rectangle", i);
        for (size_t k = 0; k < step.removed_count; ++k) {
            bool alive = true;
            must(organtex_carving_alive(carving, step.removed[k], &alive), "organtex_carving_alive");
            CHECK(!alive, "step %d: tet %u removed but alive", i, step.removed[k]);
        }
    }
    qsort(seconds, STEPS, sizeof seconds[0], compare_doubles);
    printf("%d steps: %zu tets removed, %zu faces appeared, %zu centroid texels checked\n", STEPS, removed,
           appeared, texels_checked);
    printf("step time: median %.2f ms, worst %.2f ms\n", 1e3 * seconds[STEPS / 2], 1e3 * seconds[STEPS - 1]);
    CHECK(removed > 20 * STEPS && texels_checked > appeared / 2, "too little carved or checked");

    /* Bad input: a status and a message each, and the session goes on. */
    organtex_step step;
    uint32_t past = (uint32_t)mesh.tet_count, gone_tet = 0;
    for (size_t t = 0; t < mesh.tet_count; ++t) {
        bool alive;
        must(organtex_carving_alive(carving, (uint32_t)t, &alive), "organtex_carving_alive");
        if (!alive) {
            gone_tet = (uint32_t)t;
            break;
        }
    }
    double nan_point[3] = {NAN, 0, 0}, centre[3] = {0, 0, 20};
    refused(organtex_carving_remove(carving, &past, 1, &step), ORGANTEX_INVALID_ARGUMENT, "a tet id past the mesh");
    refused(organtex_carving_remove(carving, &gone_tet, 1, &step), ORGANTEX_INVALID_ARGUMENT, "a tet removed twice");
    refused(organtex_carving_sphere(carving, nan_point, 1.0, &step), ORGANTEX_INVALID_ARGUMENT, "a NaN position");
    refused(organtex_carving_sphere(carving, centre, 0.0, &step), ORGANTEX_INVALID_ARGUMENT, "a zero radius");
    refused(organtex_carving_sphere(NULL, centre, 1.0, &step), ORGANTEX_NULL_ARGUMENT, "a NULL carving");
    refused(organtex_carving_remove(carving, NULL, 3, &step), ORGANTEX_NULL_ARGUMENT, "NULL ids with a count");
    organtex_node *none = NULL;
    refused(organtex_bake_node(bake, "liver", &none), ORGANTEX_NOT_FOUND, "a node that does not exist");
    organtex_bake *not_a_bake = NULL;
    refused(organtex_bake_open("/", &not_a_bake), ORGANTEX_INVALID_ARGUMENT, "a folder that is not a bake");
    organtex_carving_options bad = options;
    bad.texels_per_unit = 0.0;
    organtex_carving *other = NULL;
    refused(organtex_carving_new(node, &bad, &other), ORGANTEX_INVALID_ARGUMENT, "an atlas density of 0");
    uint32_t some = 0;
    for (size_t t = 0; t < mesh.tet_count; ++t) {
        bool alive;
        must(organtex_carving_alive(carving, (uint32_t)t, &alive), "organtex_carving_alive");
        if (alive) {
            some = (uint32_t)t;
            break;
        }
    }
    must(organtex_carving_remove(carving, &some, 1, &step), "a step after refusals");
    CHECK(step.removed_count == 1 && step.removed[0] == some, "the step after refusals removed %zu tets",
          step.removed_count);

    must(organtex_carving_write_glb(carving, argv[2]), "organtex_carving_write_glb");
    printf("wrote %s\n", argv[2]);

    organtex_carving_free(carving);
    organtex_node_free(node);
    organtex_bake_free(bake);
    organtex_bake_free(NULL);
    free(edges.keys);
    free(edges.counts);
    free(edges.defect);
    if (failures) {
        fprintf(stderr, "carve: %d check(s) failed\n", failures);
        return 1;
    }
    printf("every check holds\n");
    return 0;
}
