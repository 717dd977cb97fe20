// organtex.hpp: C++17 wrappers of the organtex C API (organtex.h), header
// only. Each handle is a move-only RAII class that frees it; every call
// that fails throws organtex::Error (a std::runtime_error) carrying the
// status and organtex_last_error()'s message, so a carving loop reads as
// straight-line code. Threads as in organtex.h: Bake and Node from any
// number of threads, a Carving or CutTextures from one at a time.
#ifndef ORGANTEX_HPP
#define ORGANTEX_HPP

#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "organtex.h"

namespace organtex {

// A failed call: what organtex_last_error() said, and the status.
class Error : public std::runtime_error {
public:
    Error(organtex_status status, const std::string &message)
        : std::runtime_error(message), status_(status) {}
    organtex_status status() const noexcept { return status_; }

private:
    organtex_status status_;
};

namespace detail {
inline void check(organtex_status s) {
    if (s != ORGANTEX_OK) {
        throw Error(s, std::string(organtex_status_name(s)) + ": " + organtex_last_error());
    }
}
template <typename T, void (*Free)(T *)> struct Deleter {
    void operator()(T *p) const noexcept { Free(p); }
};
template <typename T, void (*Free)(T *)> using Handle = std::unique_ptr<T, Deleter<T, Free>>;
}  // namespace detail

// The library's version string, and a check that the library's ABI is the
// header's (throws when not).
inline std::string version() { return organtex_version(); }
inline void check_abi() {
    if (organtex_abi_version() != ORGANTEX_ABI_VERSION) {
        throw Error(ORGANTEX_INVALID_ARGUMENT, "liborgantex's ABI is " +
                                                   std::to_string(organtex_abi_version()) +
                                                   ", this header's " +
                                                   std::to_string(ORGANTEX_ABI_VERSION));
    }
}

using Point = std::array<double, 3>;
using Rgb = std::array<uint8_t, 3>;

class Node;

// A node of a bake: its tet mesh and interior. Cheap to copy (shared).
class Node {
public:
    const char *name() const { return organtex_node_name(handle_.get()); }

    organtex_tet_mesh tet_mesh() const {
        organtex_tet_mesh m{};
        detail::check(organtex_node_tet_mesh(handle_.get(), &m));
        return m;
    }

    // The mesh's boundary before carving: faces (3 vertex ids each) and ids.
    struct Boundary {
        const uint32_t *faces;
        const uint32_t *ids;
        size_t count;
    };
    Boundary boundary() const {
        Boundary b{};
        detail::check(organtex_node_boundary(handle_.get(), &b.faces, &b.ids, &b.count));
        return b;
    }

    std::vector<Rgb> colours(const std::vector<Point> &points) const {
        std::vector<Rgb> out(points.size());
        detail::check(organtex_node_colours(handle_.get(), points.empty() ? nullptr : points[0].data(),
                                            points.size(), out.empty() ? nullptr : out[0].data()));
        return out;
    }

    // The block, when the interior is one (throws otherwise).
    organtex_block block() const {
        organtex_block b{};
        detail::check(organtex_node_block(handle_.get(), &b));
        return b;
    }

    const organtex_node *get() const { return handle_.get(); }

private:
    friend class Bake;
    explicit Node(organtex_node *n) : handle_(n, organtex_node_free) {}
    std::shared_ptr<organtex_node> handle_;
};

// An opened bake folder.
class Bake {
public:
    explicit Bake(const std::string &dir) {
        organtex_bake *b = nullptr;
        detail::check(organtex_bake_open(dir.c_str(), &b));
        handle_.reset(b);
    }

    std::vector<std::string> nodes() const {
        size_t n = 0;
        detail::check(organtex_bake_node_count(handle_.get(), &n));
        std::vector<std::string> names;
        for (size_t i = 0; i < n; ++i) {
            const char *name = nullptr;
            detail::check(organtex_bake_node_name(handle_.get(), i, &name));
            names.emplace_back(name);
        }
        return names;
    }

    Node node(const std::string &name) const {
        organtex_node *n = nullptr;
        detail::check(organtex_bake_node(handle_.get(), name.c_str(), &n));
        return Node(n);
    }

private:
    detail::Handle<organtex_bake, organtex_bake_free> handle_;
};

// One carving step's changes; the spans live until the carving's next call.
struct Step {
    const uint32_t *removed;
    size_t removed_count;
    const organtex_face *appeared;
    size_t appeared_count;
    const organtex_face_ref *vanished;
    size_t vanished_count;
    const organtex_rect *dirty;
    size_t dirty_count;
    const uint32_t *released;
    size_t released_count;
    bool texels_pending;
    double seconds;

    explicit Step(const organtex_step &s)
        : removed(s.removed), removed_count(s.removed_count), appeared(s.appeared),
          appeared_count(s.appeared_count), vanished(s.vanished), vanished_count(s.vanished_count),
          dirty(s.dirty), dirty_count(s.dirty_count), released(s.released),
          released_count(s.released_count), texels_pending(s.texels_pending), seconds(s.seconds) {}
};

// A carving session over a node's tet mesh.
class Carving {
public:
    explicit Carving(const Node &node, const organtex_carving_options &options = organtex_carving_options_default()) {
        organtex_carving *c = nullptr;
        detail::check(organtex_carving_new(node.get(), &options, &c));
        handle_.reset(c);
    }

    Step remove(const std::vector<uint32_t> &ids) {
        organtex_step s{};
        detail::check(organtex_carving_remove(handle_.get(), ids.empty() ? nullptr : ids.data(), ids.size(), &s));
        return Step(s);
    }

    Step sphere(const Point &centre, double radius) {
        organtex_step s{};
        detail::check(organtex_carving_sphere(handle_.get(), centre.data(), radius, &s));
        return Step(s);
    }

    Step capsule(const Point &a, const Point &b, double radius) {
        organtex_step s{};
        detail::check(organtex_carving_capsule(handle_.get(), a.data(), b.data(), radius, &s));
        return Step(s);
    }

    // Finish background texels; the pages' rectangles written since the step.
    std::vector<organtex_rect> wait() {
        const organtex_rect *dirty = nullptr;
        size_t n = 0;
        detail::check(organtex_carving_wait(handle_.get(), &dirty, &n));
        return std::vector<organtex_rect>(dirty, dirty + n);
    }

    // Page `page`'s RGBA8 texels (side x side), valid until the next step.
    std::pair<const uint8_t *, uint32_t> page(uint32_t page) const {
        const uint8_t *rgba = nullptr;
        uint32_t side = 0;
        detail::check(organtex_carving_page(handle_.get(), page, &rgba, &side));
        return {rgba, side};
    }

    bool alive(uint32_t tet) const {
        bool out = false;
        detail::check(organtex_carving_alive(handle_.get(), tet, &out));
        return out;
    }

    void write_glb(const std::string &path) {
        detail::check(organtex_carving_write_glb(handle_.get(), path.c_str()));
    }

private:
    detail::Handle<organtex_carving, organtex_carving_free> handle_;
};

// Texture for new triangles anywhere (a curved incision).
class CutTextures {
public:
    CutTextures(const Node &node, double texels_per_unit, uint32_t page_size = 1024) {
        organtex_cut_textures *t = nullptr;
        detail::check(organtex_cut_textures_new(node.get(), texels_per_unit, page_size, &t));
        handle_.reset(t);
    }

    std::vector<organtex_chart> add(const std::vector<std::array<Point, 3>> &triangles) {
        std::vector<organtex_chart> out(triangles.size());
        detail::check(organtex_cut_textures_add(handle_.get(),
                                                triangles.empty() ? nullptr : triangles[0][0].data(),
                                                triangles.size(), out.empty() ? nullptr : out.data()));
        return out;
    }

    void release(const std::vector<uint32_t> &charts) {
        detail::check(organtex_cut_textures_release(handle_.get(), charts.empty() ? nullptr : charts.data(),
                                                    charts.size()));
    }

    std::pair<const uint8_t *, uint32_t> page(uint32_t page) const {
        const uint8_t *rgba = nullptr;
        uint32_t side = 0;
        detail::check(organtex_cut_textures_page(handle_.get(), page, &rgba, &side));
        return {rgba, side};
    }

private:
    detail::Handle<organtex_cut_textures, organtex_cut_textures_free> handle_;
};

}  // namespace organtex

#endif  // ORGANTEX_HPP
