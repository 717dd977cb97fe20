// carve.cpp: the carving loop of carve.c through organtex.hpp's RAII
// wrappers, as a C++ simulator (SOFA, iMSTK) would hold them.
//
//   carve_cpp BAKE_DIR OUT.glb
//
// Carves the default bake's wall along the same tunnel, checks each new
// face's corner colours against the interior (organtex::Node::colours),
// textures a curved incision's triangles with CutTextures, checks that
// bad input throws organtex::Error with its status, and writes the carved
// surface as OUT.glb. Exit status 0 when every check holds.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "organtex.hpp"

namespace {

int failures = 0;

void check(bool ok, const char *what) {
    if (!ok) {
        std::fprintf(stderr, "carve_cpp: check failed: %s\n", what);
        ++failures;
    }
}

organtex::Point wall_path(int step) {
    double a = step / 100.0 * 0.95 * 6.283185307179586;
    return {18.5 * std::cos(a), 11.8 * std::sin(a), 20.0};
}

template <typename F> void expect_error(F call, organtex_status want, const char *what) {
    try {
        call();
        check(false, what);
    } catch (const organtex::Error &e) {
        check(e.status() == want, what);
        std::printf("  refused %-26s %s\n", what, e.what());
    }
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: carve_cpp BAKE_DIR OUT.glb\n");
        return 2;
    }
    try {
        organtex::check_abi();
        organtex::Bake bake(argv[1]);
        organtex::Node node = bake.node("uterus");
        organtex_tet_mesh mesh = node.tet_mesh();
        std::printf("organtex %s: %s has %zu tets\n", organtex::version().c_str(), node.name(), mesh.tet_count);

        organtex::Carving carving(node);
        std::vector<double> ms;
        size_t corners = 0, off = 0;
        for (int i = 1; i <= 100; ++i) {
            organtex::Step step = carving.capsule(wall_path(i - 1), wall_path(i), 1.5);
            ms.push_back(step.seconds * 1e3);
            // Corner colours against the interior, a hair inside each
            // face's own tet.
            std::vector<organtex::Point> points;
            for (size_t k = 0; k < step.appeared_count; ++k) {
                const organtex_face &f = step.appeared[k];
                const uint32_t *tet = mesh.tets + 4 * (f.id / 4);
                organtex::Point c{0, 0, 0};
                for (int v = 0; v < 4; ++v)
                    for (int a = 0; a < 3; ++a) c[a] += mesh.positions[3 * tet[v] + a] / 4.0;
                for (int v = 0; v < 3; ++v) {
                    organtex::Point p;
                    for (int a = 0; a < 3; ++a) {
                        double x = mesh.positions[3 * f.vertices[v] + a];
                        p[a] = x + (c[a] - x) * 1e-7;
                    }
                    points.push_back(p);
                }
            }
            std::vector<organtex::Rgb> want = node.colours(points);
            for (size_t k = 0; k < step.appeared_count; ++k)
                for (int v = 0; v < 3; ++v) {
                    ++corners;
                    for (int a = 0; a < 3; ++a)
                        off += std::abs(int(step.appeared[k].colours[3 * v + a]) - int(want[3 * k + v][a])) > 1;
                }
        }
        std::sort(ms.begin(), ms.end());
        std::printf("100 steps: median %.2f ms, worst %.2f ms; %zu corner colours, %zu off by more than 1\n",
                    ms[50], ms[99], corners, off);
        check(corners > 3000 && off == 0, "corner colours are the interior's");

        // A curved incision's triangles, textured from the interior.
        organtex::CutTextures incision(node, 8.0, 256);
        std::vector<std::array<organtex::Point, 3>> tris;
        for (int k = 0; k < 8; ++k) {
            double a = k * 0.2, b = (k + 1) * 0.2;
            tris.push_back({organtex::Point{18.5 * std::cos(a), 11.8 * std::sin(a), 18.0},
                            organtex::Point{18.5 * std::cos(b), 11.8 * std::sin(b), 18.0},
                            organtex::Point{18.5 * std::cos(a), 11.8 * std::sin(a), 22.0}});
        }
        std::vector<organtex_chart> charts = incision.add(tris);
        check(charts.size() == tris.size(), "a chart per incision triangle");
        auto page = incision.page(charts[0].page);
        check(page.first != nullptr && page.second == 256, "the incision's page");
        std::vector<uint32_t> ids;
        for (auto &c : charts) ids.push_back(c.chart);
        incision.release(ids);

        expect_error([&] { organtex::Bake("/nonexistent/bake"); }, ORGANTEX_INVALID_ARGUMENT, "a missing folder");
        expect_error([&] { bake.node("liver"); }, ORGANTEX_NOT_FOUND, "a node that does not exist");
        expect_error([&] { carving.remove({static_cast<uint32_t>(mesh.tet_count)}); }, ORGANTEX_INVALID_ARGUMENT,
                     "a tet id past the mesh");
        expect_error([&] { carving.sphere({0, 0, 20}, -1.0); }, ORGANTEX_INVALID_ARGUMENT, "a negative radius");
        expect_error([&] { incision.release(ids); }, ORGANTEX_INVALID_ARGUMENT, "a chart released twice");

        carving.write_glb(argv[2]);
        std::printf("wrote %s\n", argv[2]);
    } catch (const organtex::Error &e) {
        std::fprintf(stderr, "carve_cpp: %s\n", e.what());
        return 1;
    }
    if (failures) return 1;
    std::printf("every check holds\n");
    return 0;
}
