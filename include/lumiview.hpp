// lumiview.hpp: a header-only C++17 wrapper over lumiview's C API (lumiview.h).
//
// What it promises:
// - No ABI of its own. Every function here is inline and calls the C functions of lumiview.h; link
//   liblumiview exactly as a C host does. The C conventions hold unchanged (docs/ffi-conventions.md):
//   metres, candela (cd), cd/m², lumen (lm), lux, angles in degrees; matrices column-major
//   `float[16]` (glm / GL layout); enumerations are the C `LUMI_*` values as `uint32_t`; descriptors
//   are the C structs, started from the C `lumi_*_default()` functions.
// - Errors are exceptions. A C call that returns anything but `LUMI_STATUS_OK` throws `lumi::error`
//   carrying that status and the text of `lumi_last_error` copied right after the failure, on the
//   same thread. A call on an empty object (default-constructed or moved from) throws `lumi::error`
//   with `LUMI_STATUS_NULL_POINTER` without calling C (the C functions want a live context), and
//   `scene::illuminance` with no points, or point and normal lists of different lengths, throws
//   `LUMI_STATUS_INVALID_ARGUMENT` without calling C. Otherwise only the standard library's own
//   exceptions (`std::bad_alloc`) come out. Destructors never throw.
// - Ownership. `lumi::context` holds the `lumi_context *` in a `std::shared_ptr` whose deleter is
//   `lumi_context_destroy`. Every `luminaire`, `instance`, `target` and `scene` holds a copy of that
//   `shared_ptr` next to its 64-bit handle, so the C context is destroyed only after the
//   `lumi::context` and the last object made from it are all gone, whatever the order of their
//   destruction. Each destructor calls the matching `lumi_*_destroy` and ignores its status.
//   `lumi_luminaire_destroy` also destroys the luminaire's instances in C: a `lumi::instance` that
//   outlives its luminaire still exists, its calls throw `LUMI_STATUS_INVALID_ARGUMENT` (stale
//   handle), and its destructor's `lumi_instance_destroy` fails the same way, harmlessly (a handle
//   is never reused). An ignored destroy failure still sets the thread's `lumi_last_error` text.
// - The wrapper types are move-only. A moved-from object is empty: handle 0 (or no context), its
//   `operator bool` is false and its destructor does nothing.
// - Constness follows the C API: a method is `const` where its C function takes a
//   `const lumi_context *`.
// - Threading is the C API's: one thread at a time per context, and that includes every object made
//   from it, their destructors too (they call into the context). The last owner to go destroys the
//   context, on its own thread.
// - File descriptors (`exported_image`, `unique_fd`) are closed with POSIX `close()`; the export
//   itself exists only where opaque fds do (Linux), so this header is POSIX-only as it stands.
#ifndef LUMIVIEW_HPP
#define LUMIVIEW_HPP

#include "lumiview.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>  // ::close (POSIX; opaque-fd export is Linux-only anyway)

namespace lumi {

/// The name of a status as spelled in lumiview.h (`"LUMI_STATUS_IO"` …), or
/// `"LUMI_STATUS_UNKNOWN"` for a number the header does not define.
inline const char *status_name(lumi_status status) noexcept {
    switch (status) {
    case LUMI_STATUS_OK: return "LUMI_STATUS_OK";
    case LUMI_STATUS_INVALID_ARGUMENT: return "LUMI_STATUS_INVALID_ARGUMENT";
    case LUMI_STATUS_NULL_POINTER: return "LUMI_STATUS_NULL_POINTER";
    case LUMI_STATUS_UNSUPPORTED: return "LUMI_STATUS_UNSUPPORTED";
    case LUMI_STATUS_IO: return "LUMI_STATUS_IO";
    case LUMI_STATUS_PARSE: return "LUMI_STATUS_PARSE";
    case LUMI_STATUS_GPU: return "LUMI_STATUS_GPU";
    case LUMI_STATUS_DEVICE_LOST: return "LUMI_STATUS_DEVICE_LOST";
    case LUMI_STATUS_OUT_OF_MEMORY: return "LUMI_STATUS_OUT_OF_MEMORY";
    case LUMI_STATUS_BUFFER_TOO_SMALL: return "LUMI_STATUS_BUFFER_TOO_SMALL";
    case LUMI_STATUS_PANIC: return "LUMI_STATUS_PANIC";
    case LUMI_STATUS_POISONED: return "LUMI_STATUS_POISONED";
    case LUMI_STATUS_ABI_MISMATCH: return "LUMI_STATUS_ABI_MISMATCH";
    case LUMI_STATUS_NO_DEVICE: return "LUMI_STATUS_NO_DEVICE";
    default: return "LUMI_STATUS_UNKNOWN";
    }
}

/// A failed lumiview call: the C status and, as `what()`, the `lumi_last_error` text captured at the
/// moment of failure (it names the C function and the argument or file at fault). Where the text is
/// empty, `what()` is the status name.
class error : public std::runtime_error {
public:
    /// An error with status `code` and message `text`.
    error(lumi_status code, const std::string &text)
        : std::runtime_error(text.empty() ? std::string(status_name(code)) : text), status_(code) {}

    /// The C status (`LUMI_STATUS_*`; never `LUMI_STATUS_OK` in what the wrapper throws).
    lumi_status status() const noexcept { return status_; }

private:
    lumi_status status_;
};

/// The library version, decoded from `lumi_version()` (`major << 16 | minor << 8 | patch`).
struct version_info {
    uint32_t major;  ///< Major version.
    uint32_t minor;  ///< Minor version.
    uint32_t patch;  ///< Patch version.
};

/// The library's version (wraps `lumi_version`).
inline version_info version() noexcept {
    const uint32_t v = lumi_version();
    return version_info{v >> 16, (v >> 8) & 0xffu, v & 0xffu};
}

/// The ABI version the library implements (wraps `lumi_abi_version`); equals `LUMI_ABI_VERSION`
/// when header and library match. `lumi::context` does not compare them itself: the C
/// `lumi_context_create` does, and fails with `LUMI_STATUS_ABI_MISMATCH`.
inline uint32_t abi_version() noexcept { return lumi_abi_version(); }

namespace detail {

/// This thread's `lumi_last_error` text, copied (length query, then the copy).
inline std::string last_error_text() {
    const size_t len = lumi_last_error(nullptr, 0);
    if (len == 0) return std::string();
    std::vector<char> buf(len + 1, '\0');
    const size_t full = lumi_last_error(buf.data(), buf.size());
    return std::string(buf.data(), full < len ? full : len);
}

/// Throws `lumi::error` with the last-error text unless `status` is `LUMI_STATUS_OK`.
inline void check(lumi_status status) {
    if (status != LUMI_STATUS_OK) throw error(status, last_error_text());
}

/// Throws for a call on an empty (default-constructed or moved-from) object; `where` names the method.
[[noreturn]] inline void throw_empty(const char *where) {
    throw error(LUMI_STATUS_NULL_POINTER,
                std::string(where) + ": the object is empty (default-constructed or moved from)");
}

/// The context pointer shared by a `lumi::context` and everything made from it.
using context_ptr = std::shared_ptr<lumi_context>;

/// How each handle kind is destroyed (the status is ignored: destructors must not throw).
struct luminaire_kind {
    static void destroy(lumi_context *ctx, uint64_t handle) noexcept {
        (void)lumi_luminaire_destroy(ctx, handle);
    }
};
struct instance_kind {
    static void destroy(lumi_context *ctx, uint64_t handle) noexcept {
        (void)lumi_instance_destroy(ctx, handle);
    }
};
struct target_kind {
    static void destroy(lumi_context *ctx, uint64_t handle) noexcept {
        (void)lumi_target_destroy(ctx, handle);
    }
};
struct scene_kind {
    static void destroy(lumi_context *ctx, uint64_t handle) noexcept {
        (void)lumi_scene_destroy(ctx, handle);
    }
};

/// A context-owned handle plus a share of its context: move-only, destroyed with `Kind::destroy`.
/// Empty means handle 0 and no context.
template <class Kind>
class owned_handle {
public:
    owned_handle() noexcept = default;
    owned_handle(context_ptr ctx, uint64_t h) noexcept : ctx_(std::move(ctx)), handle_(h) {}
    owned_handle(const owned_handle &) = delete;
    owned_handle &operator=(const owned_handle &) = delete;
    owned_handle(owned_handle &&other) noexcept
        : ctx_(std::move(other.ctx_)), handle_(std::exchange(other.handle_, 0)) {}
    owned_handle &operator=(owned_handle &&other) noexcept {
        if (this != &other) {
            reset();
            ctx_ = std::move(other.ctx_);
            handle_ = std::exchange(other.handle_, 0);
        }
        return *this;
    }
    ~owned_handle() { reset(); }

    uint64_t handle() const noexcept { return handle_; }
    lumi_context *ctx() const noexcept { return ctx_.get(); }
    const context_ptr &shared_ctx() const noexcept { return ctx_; }
    bool empty() const noexcept { return handle_ == 0 || !ctx_; }

    /// The context for a call, or `lumi::error` (`LUMI_STATUS_NULL_POINTER`) when empty.
    lumi_context *live_ctx(const char *where) const {
        if (empty()) throw_empty(where);
        return ctx_.get();
    }

private:
    void reset() noexcept {
        if (handle_ != 0 && ctx_) Kind::destroy(ctx_.get(), handle_);
        handle_ = 0;
        ctx_.reset();
    }

    context_ptr ctx_;
    uint64_t handle_ = 0;
};

}  // namespace detail

/// An owned file descriptor, closed with POSIX `close()` on destruction unless released. Move-only;
/// empty is -1.
class unique_fd {
public:
    /// An empty fd (-1).
    unique_fd() noexcept = default;
    /// Takes ownership of `fd` (-1 for none).
    explicit unique_fd(int fd) noexcept : fd_(fd) {}
    unique_fd(const unique_fd &) = delete;
    unique_fd &operator=(const unique_fd &) = delete;
    unique_fd(unique_fd &&other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
    unique_fd &operator=(unique_fd &&other) noexcept {
        if (this != &other) {
            close_now();
            fd_ = std::exchange(other.fd_, -1);
        }
        return *this;
    }
    /// Closes the fd (errors ignored) unless it was released.
    ~unique_fd() { close_now(); }

    /// The fd, still owned by this object (-1 when empty).
    int get() const noexcept { return fd_; }
    /// Gives up ownership: returns the fd (which the caller must now close or hand to an import
    /// that takes it) and leaves this object empty.
    int release() noexcept { return std::exchange(fd_, -1); }
    /// True when it holds an fd.
    explicit operator bool() const noexcept { return fd_ >= 0; }

private:
    void close_now() noexcept {
        if (fd_ >= 0) (void)::close(fd_);
        fd_ = -1;
    }

    int fd_ = -1;
};

/// One exported image of a target (from `lumi_target_export`): the `lumi_export` fields plus
/// ownership of its new fd, which the destructor closes unless `release_fd()` was called. Hand the
/// fd to `glImportMemoryFdEXT` / a Vulkan import with `release_fd()`: a successful import takes it
/// (docs/interop.md). Move-only; a moved-from object holds no fd.
class exported_image {
public:
    /// An empty export (fd -1, all fields 0).
    exported_image() noexcept : export_{} { export_.fd = -1; }
    /// Takes ownership of `e.fd` (as returned by `lumi_target_export`).
    explicit exported_image(const lumi_export &e) noexcept : export_(e) {}
    exported_image(const exported_image &) = delete;
    exported_image &operator=(const exported_image &) = delete;
    exported_image(exported_image &&other) noexcept : export_(other.export_) { other.export_.fd = -1; }
    exported_image &operator=(exported_image &&other) noexcept {
        if (this != &other) {
            close_now();
            export_ = other.export_;
            other.export_.fd = -1;
        }
        return *this;
    }
    /// Closes the fd (errors ignored) unless it was released.
    ~exported_image() { close_now(); }

    /// The fd, still owned by this object (-1 after `release_fd()` or a move).
    int fd() const noexcept { return export_.fd; }
    /// Gives up ownership of the fd and returns it; `fd()` and `get().fd` are -1 afterwards.
    int release_fd() noexcept { return std::exchange(export_.fd, -1); }
    /// Gives up ownership of the fd and returns the whole export with it (for `lumi_vk_import` or
    /// `lumi_gl_import`, which take the fd); this object keeps the other fields, its fd -1.
    lumi_export release() noexcept {
        lumi_export e = export_;
        export_.fd = -1;
        return e;
    }
    /// The `lumi_export` fields (allocation size, formats, layout, UUIDs …); `fd` as `fd()`.
    const lumi_export &get() const noexcept { return export_; }
    /// Field access: `image->allocation_size`, `image->vk_format`, `image->width` …
    const lumi_export *operator->() const noexcept { return &export_; }
    /// True while it owns an fd.
    explicit operator bool() const noexcept { return export_.fd >= 0; }

private:
    void close_now() noexcept {
        if (export_.fd >= 0) (void)::close(export_.fd);
        export_.fd = -1;
    }

    lumi_export export_;
};

/// The two semaphore fds of a target (from `lumi_target_export_semaphores`), each owned.
struct semaphore_fds {
    unique_fd render_done;  ///< Signalled by each `lumi_render`; the host waits on it before reading.
    unique_fd host_done;    ///< Signalled by the host after its reads, once per frame.
};

/// Intensity and luminance of a far-field luminaire towards one direction
/// (`lumi_luminaire_sample`).
struct luminaire_sample {
    double intensity_cd;     ///< Luminous intensity, cd.
    double luminance_cd_m2;  ///< Luminance of the luminous opening seen from there, cd/m² (0 where
                             ///< its projected area is 0).
};

/// A host-lighting look-up table (`lumi_luminaire_lut`).
struct lut_data {
    std::vector<uint8_t> bytes;  ///< Texels in the encoding asked for (docs/lut-and-solid.md).
    double max_intensity_cd;     ///< The maximum used for normalising, cd.
};

/// One capture camera of a near-field scan (`lumi_luminaire_cameras`), in the luminaire frame.
struct capture_camera {
    std::array<double, 3> position_m;  ///< Position, metres.
    std::array<double, 3> direction;   ///< Optical axis: unit vector from the camera towards the scene.
};

/// The illuminance at points of a scene (`lumi_scene_illuminance`), one entry per point.
struct illuminance_result {
    std::vector<double> lux;           ///< Illuminance, lux.
    std::vector<double> std_error_lx;  ///< Standard error of each estimate, lux (0 where exact).
};

class context;
class luminaire;
class target;
class scene;

/// An instance of a luminaire placed in the world (a `lumi_instance` handle plus a share of its
/// context). Made by `luminaire::create_instance`; destroyed with `lumi_instance_destroy`.
class instance {
public:
    /// An empty instance (handle 0).
    instance() noexcept = default;

    /// The C handle (0 when empty).
    lumi_instance handle() const noexcept { return h_.handle(); }
    /// The C handle (0 when empty); the same as `handle()`.
    lumi_instance get() const noexcept { return h_.handle(); }
    /// True unless empty.
    explicit operator bool() const noexcept { return !h_.empty(); }

    /// Sets the model matrix (luminaire frame → world, column-major, metres). Wraps
    /// `lumi_instance_set_transform`.
    void set_transform(const float (&world_from_luminaire)[16]) {
        detail::check(lumi_instance_set_transform(h_.live_ctx("lumi::instance::set_transform"), h_.handle(),
                                                  world_from_luminaire));
    }
    /// As above, from a `std::array`.
    void set_transform(const std::array<float, 16> &world_from_luminaire) {
        detail::check(lumi_instance_set_transform(h_.live_ctx("lumi::instance::set_transform"), h_.handle(),
                                                  world_from_luminaire.data()));
    }

    /// Illuminance in lux at a world point (metres) on a surface with unit normal `normal`, from
    /// this instance alone (E = I cos i / r²). Far-field only. Wraps `lumi_instance_illuminance`.
    double illuminance(const float (&point_m)[3], const float (&normal)[3]) const {
        return illuminance_impl(point_m, normal);
    }
    /// As above, from `std::array`s.
    double illuminance(const std::array<float, 3> &point_m, const std::array<float, 3> &normal) const {
        return illuminance_impl(point_m.data(), normal.data());
    }

    /// How a near-field instance draws: `selection_mode` one of `LUMI_SELECTION_*`; `use_proxy`
    /// reprojects through the proxy mesh where the luminaire has one. From the next render. Wraps
    /// `lumi_instance_set_nearfield`.
    void set_nearfield(uint32_t selection_mode, bool use_proxy) {
        detail::check(lumi_instance_set_nearfield(h_.live_ctx("lumi::instance::set_nearfield"), h_.handle(),
                                                  selection_mode, use_proxy));
    }

private:
    friend class luminaire;
    instance(detail::context_ptr ctx, lumi_instance h) noexcept : h_(std::move(ctx), h) {}

    double illuminance_impl(const float *point_m, const float *normal) const {
        double lux = 0.0;
        detail::check(lumi_instance_illuminance(h_.live_ctx("lumi::instance::illuminance"), h_.handle(),
                                                point_m, normal, &lux));
        return lux;
    }

    detail::owned_handle<detail::instance_kind> h_;
};

/// A loaded luminaire (a `lumi_luminaire` handle plus a share of its context). Made by
/// `context::load`; destroyed with `lumi_luminaire_destroy`, which also destroys its instances in C.
class luminaire {
public:
    /// An empty luminaire (handle 0).
    luminaire() noexcept = default;

    /// The C handle (0 when empty).
    lumi_luminaire handle() const noexcept { return h_.handle(); }
    /// The C handle (0 when empty); the same as `handle()`.
    lumi_luminaire get() const noexcept { return h_.handle(); }
    /// True unless empty.
    explicit operator bool() const noexcept { return !h_.empty(); }

    /// Its kind and far-field or near-field facts (cd, lm, m). Wraps `lumi_luminaire_get_info`.
    lumi_luminaire_info info() const {
        lumi_luminaire_info out{};
        detail::check(lumi_luminaire_get_info(h_.live_ctx("lumi::luminaire::info"), h_.handle(), &out));
        return out;
    }

    /// The capture cameras of a near-field luminaire, in the scan's camera order (a size query,
    /// then the fill). Near-field only. Wraps `lumi_luminaire_cameras`.
    std::vector<capture_camera> cameras() const {
        lumi_context *ctx = h_.live_ctx("lumi::luminaire::cameras");
        size_t count = 0;
        detail::check(lumi_luminaire_cameras(ctx, h_.handle(), nullptr, nullptr, 0, &count));
        std::vector<double> positions_m(count * 3), directions(count * 3);
        size_t written = count;
        if (count != 0) {
            detail::check(lumi_luminaire_cameras(ctx, h_.handle(), positions_m.data(), directions.data(), count,
                                                 &written));
        }
        std::vector<capture_camera> out(written < count ? written : count);
        for (size_t i = 0; i < out.size(); ++i) {
            for (size_t k = 0; k < 3; ++k) {
                out[i].position_m[k] = positions_m[3 * i + k];
                out[i].direction[k] = directions[3 * i + k];
            }
        }
        return out;
    }

    /// Intensity (cd) towards (C, γ) in degrees, lumiview's Type C frame (γ 0 = nadir, −Z), and
    /// the luminance (cd/m²) of the opening seen from there. Far-field only. Wraps
    /// `lumi_luminaire_sample`.
    luminaire_sample sample(double c_deg, double gamma_deg) const {
        luminaire_sample out{0.0, 0.0};
        detail::check(lumi_luminaire_sample(h_.live_ctx("lumi::luminaire::sample"), h_.handle(), c_deg,
                                            gamma_deg, &out.intensity_cd, &out.luminance_cd_m2));
        return out;
    }

    /// A host-lighting look-up table as `desc` asks (a size query, then the fill). Far-field only.
    /// Wraps `lumi_luminaire_lut`.
    lut_data lut(const lumi_lut_desc &desc) const {
        lumi_context *ctx = h_.live_ctx("lumi::luminaire::lut");
        size_t need = 0;
        detail::check(lumi_luminaire_lut(ctx, h_.handle(), &desc, nullptr, 0, &need, nullptr));
        lut_data out{std::vector<uint8_t>(need), 0.0};
        uint8_t none = 0;  // a non-NULL buffer even for 0 bytes: NULL would be a size query again
        uint8_t *buffer = out.bytes.empty() ? &none : out.bytes.data();
        size_t written = 0;
        detail::check(lumi_luminaire_lut(ctx, h_.handle(), &desc, buffer, out.bytes.size(), &written,
                                         &out.max_intensity_cd));
        out.bytes.resize(written);
        return out;
    }
    /// The default table (`lumi_lut_desc_default()`: 2D, 360 × 181, absolute cd, f32).
    lut_data lut() const { return lut(lumi_lut_desc_default()); }

    /// Places an instance with the model matrix `world_from_luminaire` (luminaire frame → world,
    /// column-major, metres). Wraps `lumi_instance_create`.
    [[nodiscard]] instance create_instance(const float (&world_from_luminaire)[16]) {
        return create_instance_impl(world_from_luminaire);
    }
    /// As above, from a `std::array`.
    [[nodiscard]] instance create_instance(const std::array<float, 16> &world_from_luminaire) {
        return create_instance_impl(world_from_luminaire.data());
    }

private:
    friend class context;
    luminaire(detail::context_ptr ctx, lumi_luminaire h) noexcept : h_(std::move(ctx), h) {}

    instance create_instance_impl(const float *world_from_luminaire) {
        lumi_context *ctx = h_.live_ctx("lumi::luminaire::create_instance");
        lumi_instance out = 0;
        detail::check(lumi_instance_create(ctx, h_.handle(), world_from_luminaire, &out));
        return instance(h_.shared_ctx(), out);
    }

    detail::owned_handle<detail::luminaire_kind> h_;
};

/// A render target (a `lumi_target` handle plus a share of its context). Made by
/// `context::create_target`; destroyed with `lumi_target_destroy` (memory a host imported stays
/// valid).
class target {
public:
    /// An empty target (handle 0).
    target() noexcept = default;

    /// The C handle (0 when empty).
    lumi_target handle() const noexcept { return h_.handle(); }
    /// The C handle (0 when empty); the same as `handle()`.
    lumi_target get() const noexcept { return h_.handle(); }
    /// True unless empty.
    explicit operator bool() const noexcept { return !h_.empty(); }

    /// Exports one image (`which`: `LUMI_ATTACHMENT_COLOR` or `LUMI_ATTACHMENT_DEPTH`) as a new fd
    /// plus what a host needs to import it. Wraps `lumi_target_export`.
    [[nodiscard]] exported_image export_image(uint32_t which) {
        lumi_export e{};
        detail::check(lumi_target_export(h_.live_ctx("lumi::target::export_image"), h_.handle(), which, &e));
        return exported_image(e);
    }

    /// Reads one image back (`which` as for `export_image`): rows of width × bytes per pixel
    /// (RGBA16F 8, RGBA32F 16, RGBA8 4, depth 4), memory row 0 first (the row `lumi_camera.origin`
    /// names), little-endian. Fails before the first render. Wraps `lumi_target_read_pixels`: a size
    /// query (NULL buffer), then the read.
    std::vector<uint8_t> read_pixels(uint32_t which) {
        lumi_context *ctx = h_.live_ctx("lumi::target::read_pixels");
        size_t need = 0;
        detail::check(lumi_target_read_pixels(ctx, h_.handle(), which, nullptr, 0, &need));
        std::vector<uint8_t> pixels(need);
        size_t written = 0;
        detail::check(
            lumi_target_read_pixels(ctx, h_.handle(), which, pixels.data(), pixels.size(), &written));
        pixels.resize(written);
        return pixels;
    }

    /// Exports the target's two semaphores (it was created with `semaphores = true`) as new owned
    /// fds. Wraps `lumi_target_export_semaphores`; the per-frame contract is in its C doc and
    /// docs/interop.md.
    [[nodiscard]] semaphore_fds export_semaphores() {
        int32_t render_done = -1;
        int32_t host_done = -1;
        detail::check(lumi_target_export_semaphores(h_.live_ctx("lumi::target::export_semaphores"), h_.handle(),
                                                    &render_done, &host_done));
        return semaphore_fds{unique_fd(render_done), unique_fd(host_done)};
    }

private:
    friend class context;
    target(detail::context_ptr ctx, lumi_target h) noexcept : h_(std::move(ctx), h) {}

    detail::owned_handle<detail::target_kind> h_;
};

/// A loaded glTF scene (a `lumi_scene` handle plus a share of its context). Made by
/// `context::load_scene`; drawn once set with `context::set_scene`; destroyed with
/// `lumi_scene_destroy` (the context then draws no scene if it drew this one).
class scene {
public:
    /// An empty scene (handle 0).
    scene() noexcept = default;

    /// The C handle (0 when empty).
    lumi_scene handle() const noexcept { return h_.handle(); }
    /// The C handle (0 when empty); the same as `handle()`.
    lumi_scene get() const noexcept { return h_.handle(); }
    /// True unless empty.
    explicit operator bool() const noexcept { return !h_.empty(); }

    /// Illuminance (lux) at points of the scene (metres, glTF axes, +Y up) on the side each normal
    /// faces, from every instance of the context (scans by their far field), by the CPU reference
    /// path tracer; `opts` NULL for `lumi_illuminance_options_default()` (direct light plus inter-reflection).
    /// `points_m` and `normals` must have the same length, at least 1 (else
    /// `LUMI_STATUS_INVALID_ARGUMENT`, without calling C). Wraps `lumi_scene_illuminance`.
    illuminance_result illuminance(const std::vector<std::array<float, 3>> &points_m,
                                   const std::vector<std::array<float, 3>> &normals,
                                   const lumi_illuminance_options *opts = nullptr) const {
        lumi_context *ctx = h_.live_ctx("lumi::scene::illuminance");
        if (points_m.empty() || points_m.size() != normals.size()) {
            throw error(LUMI_STATUS_INVALID_ARGUMENT,
                        "lumi::scene::illuminance: " + std::to_string(points_m.size()) + " points but " +
                            std::to_string(normals.size()) + " normals");
        }
        std::vector<float> p(points_m.size() * 3), n(normals.size() * 3);
        for (size_t i = 0; i < points_m.size(); ++i) {
            for (size_t k = 0; k < 3; ++k) {
                p[3 * i + k] = points_m[i][k];
                n[3 * i + k] = normals[i][k];
            }
        }
        illuminance_result out{std::vector<double>(points_m.size()), std::vector<double>(points_m.size())};
        detail::check(lumi_scene_illuminance(ctx, h_.handle(), p.data(), n.data(), points_m.size(), opts,
                                             out.lux.data(), out.std_error_lx.data()));
        return out;
    }
    /// As above with the options given by value.
    illuminance_result illuminance(const std::vector<std::array<float, 3>> &points_m,
                                   const std::vector<std::array<float, 3>> &normals,
                                   const lumi_illuminance_options &opts) const {
        return illuminance(points_m, normals, &opts);
    }

private:
    friend class context;
    scene(detail::context_ptr ctx, lumi_scene h) noexcept : h_(std::move(ctx), h) {}

    detail::owned_handle<detail::scene_kind> h_;
};

/// A lumiview context: a Vulkan device and everything rendered with it. Holds the `lumi_context *`
/// in a `std::shared_ptr` (deleter `lumi_context_destroy`) shared with every luminaire, instance and
/// target made from it, so the C context lives until the last of them is gone. Move-only; a
/// moved-from context is empty and its calls throw `LUMI_STATUS_NULL_POINTER`.
class context {
public:
    /// A context with `lumi_context_desc_default()` (first discrete, integrated, then software
    /// device; no validation, no log). Wraps `lumi_context_create`.
    context() : context(lumi_context_desc_default()) {}

    /// A context as `desc` says (start from `lumi_context_desc_default()`). Wraps
    /// `lumi_context_create`; `LUMI_STATUS_ABI_MISMATCH` when `desc.abi_version` is not the
    /// library's ABI.
    explicit context(const lumi_context_desc &desc) : ctx_(create(desc)) {}

    context(const context &) = delete;
    context &operator=(const context &) = delete;
    /// Moves the share of the context; `other` becomes empty.
    context(context &&other) noexcept = default;
    /// Drops this object's share (the C context goes when no object holds one) and takes `other`'s.
    context &operator=(context &&other) noexcept = default;
    /// Drops this object's share; `lumi_context_destroy` runs when no object holds one.
    ~context() = default;

    /// The C context (NULL when empty), still owned by the wrapper objects.
    lumi_context *get() const noexcept { return ctx_.get(); }
    /// The shared owner of the C context (empty when this object is).
    const std::shared_ptr<lumi_context> &shared() const noexcept { return ctx_; }
    /// True unless empty (moved from).
    explicit operator bool() const noexcept { return static_cast<bool>(ctx_); }

    /// What the device can do and who it is. Wraps `lumi_context_caps`.
    lumi_device_caps caps() const {
        lumi_device_caps out{};
        detail::check(lumi_context_caps(live("lumi::context::caps"), &out));
        return out;
    }

    /// Loads a luminaire (IES, EULUMDAT, `.lvpack`, scan manifest, TM-25 ray file; detected from
    /// the first bytes) with the default description. `path` is UTF-8. Wraps `lumi_luminaire_load`.
    [[nodiscard]] luminaire load(const std::string &path) {
        lumi_luminaire out = 0;
        detail::check(lumi_luminaire_load(live("lumi::context::load"), path.c_str(), &out));
        return luminaire(ctx_, out);
    }

    /// Loads a luminaire with a description (near-field budget, proxy, content radius, cache
    /// folder; start from `lumi_luminaire_desc_default()`). Wraps `lumi_luminaire_load_ex`.
    [[nodiscard]] luminaire load(const std::string &path, const lumi_luminaire_desc &desc) {
        lumi_luminaire out = 0;
        detail::check(lumi_luminaire_load_ex(live("lumi::context::load"), path.c_str(), &desc, &out));
        return luminaire(ctx_, out);
    }

    /// Creates a render target (start from `lumi_target_desc_default()`). Wraps
    /// `lumi_target_create`.
    [[nodiscard]] target create_target(const lumi_target_desc &desc) {
        lumi_target out = 0;
        detail::check(lumi_target_create(live("lumi::context::create_target"), &desc, &out));
        return target(ctx_, out);
    }
    /// A target with `lumi_target_desc_default()` (1280 × 720, RGBA32F, R32F depth, exportable).
    [[nodiscard]] target create_target() { return create_target(lumi_target_desc_default()); }

    /// Loads a glTF 2.0 scene (`.glb`, or `.gltf` with its files; metres, +Y up). `path` is UTF-8.
    /// Wraps `lumi_scene_load`.
    [[nodiscard]] scene load_scene(const std::string &path) {
        lumi_scene out = 0;
        detail::check(lumi_scene_load(live("lumi::context::load_scene"), path.c_str(), &out));
        return scene(ctx_, out);
    }

    /// Draws `s` in every later render, lit by this context's instances. Wraps
    /// `lumi_context_set_scene`; `s` must come from this context.
    void set_scene(const scene &s) {
        lumi_context *ctx = live("lumi::context::set_scene");
        if (!s) detail::throw_empty("lumi::context::set_scene (an empty scene)");
        detail::check(lumi_context_set_scene(ctx, s.handle()));
    }
    /// Draws no scene from the next render on (`lumi_context_set_scene(ctx, 0)`).
    void clear_scene() { detail::check(lumi_context_set_scene(live("lumi::context::clear_scene"), 0)); }

    /// How the drawn scene is lit (start from `lumi_scene_settings_default()`). Wraps
    /// `lumi_context_set_scene_settings`.
    void set_scene_settings(const lumi_scene_settings &settings) {
        detail::check(lumi_context_set_scene_settings(live("lumi::context::set_scene_settings"), &settings));
    }

    /// Renders every instance of this context into `into`, seen by `camera`; `options` NULL for
    /// `lumi_render_options_default()`. Returns after the GPU finished (unless the target has
    /// semaphores). Wraps `lumi_render`.
    void render(target &into, const lumi_camera &camera, const lumi_render_options *options) {
        lumi_context *ctx = live("lumi::context::render");
        if (!into) detail::throw_empty("lumi::context::render (an empty target)");
        detail::check(lumi_render(ctx, into.handle(), &camera, options));
    }
    /// As above with the default options.
    void render(target &into, const lumi_camera &camera) { render(into, camera, nullptr); }

private:
    static detail::context_ptr create(const lumi_context_desc &desc) {
        lumi_context *raw = nullptr;
        detail::check(lumi_context_create(&desc, &raw));
        // If the control block cannot be allocated, shared_ptr calls the deleter before throwing.
        return detail::context_ptr(raw, [](lumi_context *c) noexcept { lumi_context_destroy(c); });
    }

    lumi_context *live(const char *where) const {
        if (!ctx_) detail::throw_empty(where);
        return ctx_.get();
    }

    detail::context_ptr ctx_;
};

}  // namespace lumi

#endif  // LUMIVIEW_HPP
