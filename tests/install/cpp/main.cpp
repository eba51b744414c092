// C++17 consumer of an installed lumiview (lumiview.hpp over lumiview.h), built by CMake with
// find_package(lumiview 0.1 CONFIG REQUIRED) and lumiview::lumiview.
//
//   cpp_consumer PHOTOMETRY_FILE [SCENE]   (an IES or EULUMDAT file with a luminous opening; a glTF
//                                           scene with open floor at x = z = 0, e.g. the office)
//
// Checks, one line each ending in PASS (or FAIL with the reason), exit status non-zero on any
// failure:
//   1. version and ABI: lumi::abi_version() equals LUMI_ABI_VERSION of the header compiled against;
//   2. a context with the defaults;
//   3. the file loads as a far-field luminaire with flux > 0;
//   4. one instance (identity model: luminaire frame = world, +Z up, nadir −Z) seen from 2 m
//      straight below (eye (0, 0, −2) looking up at the photometric centre) into a 64 × 64 RGBA32F
//      read-back target: the centre pixel's luminance (R, cd/m²) is finite, > 0 and within 2 % of
//      luminaire.sample(0, 0).luminance_cd_m2, the luminance of the opening seen from straight
//      below (γ 0 = nadir, docs/conventions.md);
//   5. loading "/nonexistent/x.ies" throws lumi::error with LUMI_STATUS_IO naming the path;
//   6. a moved-from luminaire is empty (handle 0, false) and a call on it throws lumi::error;
//   7. with SCENE: the luminaire hung 2.95 m above the scene's floor point (0, 0, 0), nadir down
//      (model columns X → +X, Y → −Z, Z → +Y); the direct illuminance there is within 3 % of
//      I(0, 0)/h² (the point formula: the opening's near field is below 3 % at 2.95 m), the total is
//      larger (inter-reflection), both with a standard error; the scene is set and cleared on the
//      context; an empty point list throws LUMI_STATUS_INVALID_ARGUMENT.
#include <lumiview.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <utility>
#include <vector>

namespace {

constexpr uint32_t kSizePx = 64;
constexpr double kEyeDistanceM = 2.0;
constexpr double kLuminanceTolerance = 0.02;

using mat4 = std::array<float, 16>;  // column-major: element (row r, column c) at [c * 4 + r]

struct vec3 {
    double x, y, z;
};

vec3 sub(vec3 a, vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
vec3 cross(vec3 a, vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
vec3 normalize(vec3 a) {
    const double l = std::sqrt(dot(a, a));
    return {a.x / l, a.y / l, a.z / l};
}

// Right-handed look-at (world → eye; the eye looks down its −Z), like gluLookAt.
mat4 look_at(vec3 eye, vec3 centre, vec3 up) {
    const vec3 f = normalize(sub(centre, eye));
    const vec3 s = normalize(cross(f, up));
    const vec3 u = cross(s, f);
    return {static_cast<float>(s.x), static_cast<float>(u.x), static_cast<float>(-f.x), 0.0f,
            static_cast<float>(s.y), static_cast<float>(u.y), static_cast<float>(-f.y), 0.0f,
            static_cast<float>(s.z), static_cast<float>(u.z), static_cast<float>(-f.z), 0.0f,
            static_cast<float>(-dot(s, eye)), static_cast<float>(-dot(u, eye)), static_cast<float>(dot(f, eye)),
            1.0f};
}

// GL perspective projection (clip z in −w…w), like gluPerspective, from the focal factor
// f = 1 / tan(fovy / 2).
mat4 perspective_gl(double focal, double aspect, double near_m, double far_m) {
    mat4 m{};
    m[0] = static_cast<float>(focal / aspect);
    m[5] = static_cast<float>(focal);
    m[10] = static_cast<float>((far_m + near_m) / (near_m - far_m));
    m[11] = -1.0f;
    m[14] = static_cast<float>(2.0 * far_m * near_m / (near_m - far_m));
    return m;
}

int g_failures = 0;

void report(const std::string &check, bool ok, const std::string &detail) {
    if (ok) {
        std::printf("%s: %s: PASS\n", check.c_str(), detail.c_str());
    } else {
        std::printf("%s: %s: FAIL\n", check.c_str(), detail.c_str());
        ++g_failures;
    }
    std::fflush(stdout);
}

std::string fmt(const char *format, double a, double b = 0.0, double c = 0.0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, format, a, b, c);
    return buf;
}

// The little-endian float at byte offset `at` (x86-64 and AArch64 hosts are little-endian).
float float_at(const std::vector<uint8_t> &bytes, size_t at) {
    float v = 0.0f;
    std::memcpy(&v, bytes.data() + at, sizeof v);
    return v;
}

void check_version() {
    const lumi::version_info v = lumi::version();
    const uint32_t abi = lumi::abi_version();
    char detail[128];
    std::snprintf(detail, sizeof detail, "lumiview %u.%u.%u, ABI %u (header %u)", v.major, v.minor, v.patch, abi,
                  static_cast<unsigned>(LUMI_ABI_VERSION));
    report("version", abi == LUMI_ABI_VERSION, detail);
}

// The render check (4.). The field of view is chosen from the opening so that its smaller side
// spans the image height: pixel (32, 32), whose centre is half a pixel (1/128 of that side) off the
// image centre along each axis, then lies well inside the opening for any file, and sees it less
// than 0.2° off the nadir for openings up to 0.5 m.
void check_render(lumi::context &ctx, lumi::luminaire &lum, const lumi_luminaire_info &info) {
    const double x_m = info.opening_size_m[0], y_m = info.opening_size_m[1];
    const double smaller_m = (x_m > 0.0 && y_m > 0.0) ? std::min(x_m, y_m) : std::max(x_m, y_m);
    if (!(smaller_m > 0.0)) {
        report("render", false, "the file has no luminous opening seen from below (point source)");
        return;
    }
    const std::array<float, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    lumi::instance inst = lum.create_instance(identity);

    lumi_target_desc td = lumi_target_desc_default();
    td.width = kSizePx;
    td.height = kSizePx;
    td.color_format = LUMI_COLOR_RGBA32F;
    td.depth_format = LUMI_DEPTH_NONE;
    td.exportable = false;
    lumi::target tgt = ctx.create_target(td);

    // Eye 2 m below the photometric centre, looking up (+Z); world +Z is up, so the image's up is
    // +Y (C90). The half-height seen at the opening's distance is half the smaller side.
    lumi_camera cam = lumi_camera_default();  // GL depth range, bottom-left origin
    const mat4 view = look_at({0.0, 0.0, -kEyeDistanceM}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0});
    const mat4 proj = perspective_gl(kEyeDistanceM / (0.5 * smaller_m), 1.0, 0.05, 20.0);
    std::memcpy(cam.view, view.data(), sizeof cam.view);
    std::memcpy(cam.projection, proj.data(), sizeof cam.projection);
    ctx.render(tgt, cam);

    const std::vector<uint8_t> px = tgt.read_pixels(LUMI_ATTACHMENT_COLOR);
    const size_t expect_bytes = size_t{kSizePx} * kSizePx * 16;
    if (px.size() != expect_bytes) {
        report("render", false, fmt("read_pixels gave %.0f bytes, expected %.0f", static_cast<double>(px.size()),
                                    static_cast<double>(expect_bytes)));
        return;
    }
    const size_t centre = (size_t{kSizePx / 2} * kSizePx + kSizePx / 2) * 16;
    const double rendered = float_at(px, centre);
    const double alpha = float_at(px, centre + 12);
    const double expected = lum.sample(0.0, 0.0).luminance_cd_m2;
    const bool ok = std::isfinite(rendered) && rendered > 0.0 && expected > 0.0 &&
                    std::fabs(rendered - expected) <= kLuminanceTolerance * expected;
    report("render centre pixel",
           ok,
           fmt("L %.6g cd/m2 vs sample(0, 0) %.6g cd/m2 (alpha %.3g)", rendered, expected, alpha));
}

void check_missing_file(lumi::context &ctx) {
    const std::string bad = "/nonexistent/x.ies";
    try {
        (void)ctx.load(bad);
        report("missing file", false, "loading " + bad + " did not throw");
    } catch (const lumi::error &e) {
        const bool ok = e.status() == LUMI_STATUS_IO && std::string(e.what()).find(bad) != std::string::npos;
        report("missing file", ok, std::string(lumi::status_name(e.status())) + ": " + e.what());
    }
}

void check_moved_from(lumi::luminaire &lum) {
    lumi::luminaire moved = std::move(lum);
    bool ok = moved && moved.handle() != 0 && !lum && lum.handle() == 0 && lum.get() == 0;
    std::string detail = "moved-from handle 0, new owner holds it";
    try {
        (void)lum.info();
        ok = false;
        detail += "; info() on the moved-from luminaire did not throw";
    } catch (const lumi::error &e) {
        ok = ok && e.status() == LUMI_STATUS_NULL_POINTER;
        detail += std::string("; info() on it throws ") + lumi::status_name(e.status());
    }
    report("moved-from luminaire", ok, detail);
    lum = std::move(moved);  // hand it back (move assignment into an empty object)
}

void check_scene(lumi::context &ctx, lumi::luminaire &lum, const char *scene_path) {
    constexpr float kHeightM = 2.95f;
    lumi::scene room = ctx.load_scene(scene_path);
    ctx.set_scene(room);
    const std::array<float, 16> hung{1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, kHeightM, 0, 1};
    lumi::instance inst = lum.create_instance(hung);
    const std::vector<std::array<float, 3>> points{{0.0f, 0.0f, 0.0f}};
    const std::vector<std::array<float, 3>> up{{0.0f, 1.0f, 0.0f}};
    lumi_illuminance_options direct = lumi_illuminance_options_default();
    direct.light = LUMI_ILLUMINANCE_DIRECT;
    const lumi::illuminance_result d = room.illuminance(points, up, direct);
    const lumi::illuminance_result t = room.illuminance(points, up);
    const double want = lum.sample(0.0, 0.0).intensity_cd / (double{kHeightM} * kHeightM);
    const bool ok = d.lux.size() == 1 && t.lux.size() == 1 && std::fabs(d.lux[0] / want - 1.0) < 0.03 &&
                    t.lux[0] > d.lux[0] && t.std_error_lx[0] > 0.0;
    report("scene illuminance", ok,
           fmt("direct %.6g lx vs I(0, 0)/h2 %.6g lx; total %.6g lx", d.lux[0], want, t.lux[0]));
    ctx.clear_scene();
    try {
        (void)room.illuminance({}, {});
        report("scene empty list", false, "illuminance of no points did not throw");
    } catch (const lumi::error &e) {
        report("scene empty list", e.status() == LUMI_STATUS_INVALID_ARGUMENT, lumi::status_name(e.status()));
    }
}

int run(const char *path, const char *scene_path) {
    check_version();

    lumi::context ctx;
    const lumi_device_caps caps = ctx.caps();
    report("context", static_cast<bool>(ctx),
           std::string("adapter '") + caps.adapter_name + "'" + (caps.is_cpu ? " (software)" : ""));

    lumi::luminaire lum = ctx.load(path);
    const lumi_luminaire_info info = lum.info();
    char detail[256];
    std::snprintf(detail, sizeof detail, "%s: kind %u, flux %.6g lm, opening %.4g m x %.4g m", path,
                  static_cast<unsigned>(info.kind), info.flux_lm, info.opening_size_m[0], info.opening_size_m[1]);
    report("load", info.kind == LUMI_LUMINAIRE_FARFIELD && info.flux_lm > 0.0, detail);

    check_render(ctx, lum, info);
    check_missing_file(ctx);
    if (scene_path != nullptr) check_scene(ctx, lum, scene_path);
    check_moved_from(lum);

    if (g_failures != 0) {
        std::printf("cpp consumer: %d check(s) failed\n", g_failures);
        return 1;
    }
    std::printf("cpp consumer: all checks passed\n");
    return 0;
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 2 && argc != 3) {
        std::fprintf(stderr, "usage: cpp_consumer PHOTOMETRY_FILE [SCENE]\n");
        return 2;
    }
    try {
        return run(argv[1], argc == 3 ? argv[2] : nullptr);
    } catch (const lumi::error &e) {
        std::fprintf(stderr, "cpp consumer: lumi::error %s (%u): %s\n", lumi::status_name(e.status()),
                     static_cast<unsigned>(e.status()), e.what());
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cpp consumer: %s\n", e.what());
    }
    return 1;
}
