#include "remesh/decimate.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <string>
#include <unordered_map>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/errors.h"
#include "remesh/quadric.h"

namespace normalflow {
namespace {

using detail::Quadric;

/// The weight of the edge-length term in a collapse's cost, relative to the quadric error: among
/// collapses of equal error (a flat patch, where all are zero) the shorter edge goes first, so that a
/// flat region is decimated evenly instead of into fans of slivers around a few vertices (which also
/// makes the decimation quadratic there). On fandisk extracted at 256 to 20,000 faces, Hausdorff
/// distance: 1e-3 0.00767, 1e-4 0.00681; 0 did not finish in a minute (the fans).
constexpr double kLengthWeight = 1e-4;
/// The pull of the merged vertex towards the edge's midpoint, relative to the quadric's mean
/// eigenvalue: small enough to leave a corner where its planes meet, and it picks the point of a
/// crease line or a flat patch nearest to the midpoint, where the quadric alone has no single minimum.
constexpr double kRegularisation = 1e-3;
/// Each pass considers the cheaper part of the open edges, in order of cost (see select).
constexpr double kPassFraction = 0.25;
/// With tangent planes: eigenvalues of a quadric below this fraction of its largest count as zero.
/// Fandisk extracted at 256 and decimated by tangent planes within 0.03 voxel, mean normal error against
/// the true fandisk: 0.02 0.83°, 0.1 0.89°, 0.3 0.90°; the regularised solve (minimiser_near) 0.84°.
constexpr double kTruncation = 0.02;

/// A slot per face corner: the edge from that corner to the next. Its candidate key is the collapse's
/// cost as float bits (a non-negative float orders as its bits do) over the slot index, so that sorting
/// the keys orders by cost with ties broken by the slot: deterministic, and 8 bytes to sort.
constexpr std::uint64_t kNoCandidate = ~std::uint64_t(0);
/// A slot's state: a candidate; refused by the checks (until its neighbourhood changes); or over
/// QemOptions::max_error (until its ends move).
constexpr std::uint8_t kOpen = 0, kRefused = 1, kOverBound = 2;

/// Where the merged vertex of a slot's edge goes, and the quadric error there, as costed.
struct Placement {
    Vec3f x;
    float error;
};

/// The inner angle (degrees) below which two neighbouring faces count as folded onto each other: a decimation makes
/// no fold sharper than this unless the faces there were already that sharp (QemDecimation::allowed).
constexpr double kMinFoldDeg = 30.0;
/// An error-bounded decimation ends at the first pass that removes fewer than this fraction of the faces.
constexpr double kTailFraction = 0.002;
const double kCosFold = -std::cos(kMinFoldDeg * std::numbers::pi / 180.0);

double quality(const Vec3d& a, const Vec3d& b, const Vec3d& c, Vec3d* normal) {
    const Vec3d n = cross(b - a, c - a);
    if (normal) *normal = n;
    const double l2 = squared_norm(b - a) + squared_norm(c - b) + squared_norm(a - c);
    return l2 > 0 ? 2.0 * std::numbers::sqrt3 * norm(n) / l2 : 0.0;  // 4√3 · area / Σ l², area = |n|/2
}

/// A vertex's face list: up to kInline faces in place (an extraction's vertices have about six), more on
/// the heap. The decimation's lists then sit in one array instead of a heap block each: the set-up makes
/// no allocation per vertex, and the passes' walks over neighbourhoods stay in that array.
class FaceList {
public:
    static constexpr std::uint32_t kInline = 10;
    FaceList() = default;
    FaceList(const FaceList&) = delete;
    FaceList& operator=(const FaceList&) = delete;
    ~FaceList() { release(); }
    const std::uint32_t* begin() const { return cap_ > kInline ? heap_ : inline_; }
    const std::uint32_t* end() const { return begin() + size_; }
    std::uint32_t size() const { return size_; }
    void push_back(std::uint32_t f) {
        if (size_ == std::max(cap_, kInline)) grow(2 * size_);
        data()[size_++] = f;
    }
    void assign(const std::uint32_t* first, const std::uint32_t* last) {
        size_ = 0;
        if (std::uint32_t(last - first) > std::max(cap_, kInline)) grow(std::uint32_t(last - first));
        std::copy(first, last, data());
        size_ = std::uint32_t(last - first);
    }
    void clear() { size_ = 0; }
    /// Frees the heap block, if any, and empties the list.
    void reset() {
        release();
        size_ = 0;
    }
    template <class Pred>
    void remove_if(Pred dead) {
        std::uint32_t* d = data();
        size_ = std::uint32_t(std::remove_if(d, d + size_, dead) - d);
    }

private:
    std::uint32_t* data() { return cap_ > kInline ? heap_ : inline_; }
    void grow(std::uint32_t want) {
        auto* fresh = new std::uint32_t[want];
        std::copy(begin(), end(), fresh);
        release();
        heap_ = fresh;
        cap_ = want;
    }
    void release() {
        if (cap_ > kInline) delete[] heap_;
        cap_ = 0;
    }
    union {
        std::uint32_t inline_[kInline];
        std::uint32_t* heap_;
    };
    std::uint32_t size_ = 0, cap_ = 0;  ///< cap_ > kInline: the faces are on the heap
};

class QemDecimation {
public:
    QemDecimation(Mesh& m, const QemOptions& o) : m_(m), opt_(o) {
        const std::size_t nv = m.positions.size(), nf = m.triangles.size();
        tris_ = m.triangles;
        pos_.resize(nv);
        locked_.assign(nv, 0);
        alive_f_.assign(nf, 1);
        // The faces of each vertex, in face order (a counting sort).
        std::vector<std::uint32_t> start(nv + 1, 0), list(3 * nf);
        for (const Tri& t : tris_)
            for (const std::uint32_t v : t) ++start[v + 1];
        for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
        {
            std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
            for (std::uint32_t f = 0; f < nf; ++f)
                for (const std::uint32_t v : tris_[f]) list[next[v]++] = f;
        }
        q_.assign(nv, {});
        vf_ = std::vector<FaceList>(nv);
        const bool tangent = o.tangent_planes;  // decimate_mesh_qem checked that m has a normal per vertex
        // Per vertex, in parallel (each writes its own entries only): its quadric, summed over its faces
        // in face order; its face list; and whether it is locked: on a border or non-manifold edge (an
        // edge with other than two faces) or on a face with a repeated vertex.
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1024), [&](const auto& r) {
            std::vector<std::pair<std::uint32_t, int>> edges;  // (neighbour, faces on the edge to it)
            for (std::size_t v = r.begin(); v != r.end(); ++v) {
                pos_[v] = Vec3d(m.positions[v]);
                const bool own = tangent && squared_norm(Vec3d(m.normals[v])) > 0;
                double area = 0.0;
                edges.clear();
                for (std::uint32_t i = start[v]; i < start[v + 1]; ++i) {
                    const std::uint32_t f = list[i];
                    const Tri& t = tris_[f];
                    // the face's plane (computed for each of its corners: cheaper than storing it)
                    const Vec3d p0(m.positions[t[0]]), p1(m.positions[t[1]]), p2(m.positions[t[2]]);
                    const Vec3d n = cross(p1 - p0, p2 - p0);
                    if (const double len = norm(n); len > 0) {
                        if (own) {
                            area += len / 6.0;
                        } else {
                            const Vec3d u = n / len;
                            q_[v].add_plane(u, -dot(u, p0), 0.5 * len);
                        }
                    }
                    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
                        locked_[v] = 1;
                        continue;
                    }
                    for (const std::uint32_t w : t) {
                        if (w == v) continue;
                        auto e = std::find_if(edges.begin(), edges.end(), [&](const auto& x) { return x.first == w; });
                        if (e == edges.end())
                            edges.push_back({w, 1});
                        else
                            ++e->second;
                    }
                }
                for (const auto& e : edges)
                    if (e.second != 2) locked_[v] = 1;
                if (area > 0) {
                    const Vec3d u = normalized(Vec3d(m.normals[v]));
                    q_[v].add_plane(u, -dot(u, pos_[v]), area);
                }
                vf_[v].assign(list.data() + start[v], list.data() + start[v + 1]);
            }
        });
        faces_ = nf;
        cos_max_ = std::cos(opt_.max_normal_change_deg * std::numbers::pi / 180.0);
        if (opt_.max_normal_deviation_deg > 0) {  // decimate_mesh_qem checked that m has a normal per vertex
            cos_deviation_ = std::cos(opt_.max_normal_deviation_deg * std::numbers::pi / 180.0);
            normal_.resize(nv);
            for (std::size_t v = 0; v < nv; ++v) {
                const Vec3d n(m.normals[v]);
                const double len = norm(n);
                normal_[v] = len > 0 ? n / len : Vec3d{};
            }
        }
        max_error2_ = opt_.max_error * opt_.max_error;
    }

    QemReport run() {
        QemReport rep;
        rep.faces_before = m_.triangles.size();
        rep.vertices_before = m_.positions.size();
        const std::size_t nv = pos_.size();
        std::vector<std::uint64_t> cand;
        std::vector<std::uint8_t> taken(nv);
        std::vector<std::uint32_t> selected;
        std::vector<double> made_error;
        // At first every edge needs costing.
        dirty_.assign(nv, 1);
        changed_.assign(nv, 1);
        while (faces_ > opt_.target_faces) {
            if (2 * faces_ < tris_.size()) compact_faces();  // later passes cost what is left, not what was
            cost_edges();
            std::fill(dirty_.begin(), dirty_.end(), 0);
            std::fill(changed_.begin(), changed_.end(), 0);
            select(cand, taken, selected);
            if (selected.empty()) break;  // nothing left that passes the checks
            // Near the target, only the cheapest of them (each collapse removes two faces).
            const std::size_t room = (faces_ - opt_.target_faces + 1) / 2;
            if (selected.size() > room) selected.resize(room);  // in order of cost
            // The selected collapses share no vertex and no face, and none reads what another writes:
            // they are made in parallel, each the same on any number of threads.
            made_error.assign(selected.size(), -1.0);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, selected.size(), 256), [&](const auto& r) {
                Scratch sc;
                for (std::size_t i = r.begin(); i != r.end(); ++i) made_error[i] = try_collapse(selected[i], sc);
            });
            std::size_t made = 0;
            for (std::size_t i = 0; i < selected.size(); ++i)
                if (made_error[i] >= 0) {
                    ++made;
                    rep.max_error = std::max(rep.max_error, made_error[i]);
                }
            faces_ -= 2 * made;
            rep.collapses += made;
            // Bounded by max_error alone (no count to reach): a pass that removes under kTailFraction of the faces
            // ends it. Refused edges reopen whenever a neighbour changes, and a normal bound refuses many: the tail
            // of such passes, each the cost of a whole pass, took 100 s for the last few faces of a 1.3 M-face shell.
            if (opt_.target_faces == 0 && double(2 * made) < kTailFraction * double(faces_)) break;
        }
        write_back();
        rep.faces_after = m_.triangles.size();
        rep.vertices_after = m_.positions.size();
        rep.reached_target = opt_.target_faces == 0 || rep.faces_after <= opt_.target_faces;
        return rep;
    }

private:
    /// Per-thread scratch of a collapse's checks.
    struct Scratch {
        std::vector<std::uint32_t> shared, nk, ng, common;
        /// the merged vertex's faces: their two other corners and their normal (unit) before and after
        struct Fan {
            std::uint32_t a, b;
            int side;  ///< 0: a face of keep, 1: of gone (before the collapse)
            Vec3d before, after;
        };
        std::vector<Fan> fan;
    };

    /// Costs the edges of the alive faces into their slots (3 per face), each edge once (from the face
    /// where it runs low → high, in a consistently oriented mesh; a border or non-manifold edge has
    /// locked ends and is skipped). Only edges at a dirty vertex are costed again; a refused edge is
    /// reconsidered once its neighbourhood changed. In parallel, into fixed slots: the same keys on any
    /// number of threads.
    void cost_edges() {
        keys_.resize(3 * tris_.size(), kNoCandidate);
        place_.resize(3 * tris_.size());
        state_.resize(3 * tris_.size(), kOpen);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tris_.size(), 4096), [&](const auto& r) {
            for (std::size_t f = r.begin(); f != r.end(); ++f)
                for (int k = 0; k < 3; ++k) {
                    const std::size_t slot = 3 * f + std::size_t(k);
                    const std::uint32_t a = tris_[f][k], b = tris_[f][(k + 1) % 3];
                    if (!alive_f_[f] || a >= b || (locked_[a] && locked_[b])) {
                        keys_[slot] = kNoCandidate;
                    } else if (dirty_[a] || dirty_[b] || keys_[slot] == kNoCandidate) {
                        keys_[slot] = cost(a, b, slot);
                        state_[slot] = max_error2_ > 0 && double(place_[slot].error) > max_error2_ * (q_[a].w + q_[b].w)
                                           ? kOverBound
                                           : kOpen;
                    } else if (state_[slot] == kRefused && (changed_[a] || changed_[b])) {
                        state_[slot] = kOpen;
                    }
                }
        });
    }

    /// The collapses of a pass, cheapest first: among the cheaper part of the open edges, in order of
    /// cost, each edge neither of whose ends is at or next to an end of an edge taken before it. So no
    /// two of them share a vertex or a face or read what another's collapse writes.
    void select(std::vector<std::uint64_t>& cand, std::vector<std::uint8_t>& taken,
                std::vector<std::uint32_t>& selected) const {
        // The cheaper part: a histogram of the open keys' top 16 bits (the cost's sign, exponent and 7
        // bits of mantissa) in fixed blocks gives the bucket below which about kPassFraction of them lie;
        // the keys up to it are gathered in slot order. Integer counts: the same on any number of threads.
        constexpr std::size_t kBlocks = 16, kBuckets = std::size_t(1) << 16;
        const std::size_t n = keys_.size(), per = (n + kBlocks - 1) / kBlocks;
        hist_.assign(kBlocks * kBuckets, 0);
        const auto open = [&](std::size_t slot) { return keys_[slot] != kNoCandidate && state_[slot] == kOpen; };
        tbb::parallel_for(std::size_t(0), kBlocks, [&](std::size_t b) {
            std::uint32_t* h = hist_.data() + b * kBuckets;
            for (std::size_t slot = b * per; slot < std::min(n, (b + 1) * per); ++slot)
                if (open(slot)) ++h[keys_[slot] >> 48];
        });
        std::size_t total = 0;
        for (const std::uint32_t c : hist_) total += c;
        selected.clear();
        if (total == 0) return;
        const std::size_t part = std::max<std::size_t>(1, std::size_t(double(total) * kPassFraction));
        std::size_t below = 0, bucket = 0;
        for (; bucket < kBuckets; ++bucket) {
            for (std::size_t b = 0; b < kBlocks; ++b) below += hist_[b * kBuckets + bucket];
            if (below >= part) break;
        }
        std::size_t offset[kBlocks + 1] = {};
        for (std::size_t b = 0; b < kBlocks; ++b) {
            std::size_t c = 0;
            for (std::size_t k = 0; k <= bucket; ++k) c += hist_[b * kBuckets + k];
            offset[b + 1] = offset[b] + c;
        }
        cand.resize(below);
        tbb::parallel_for(std::size_t(0), kBlocks, [&](std::size_t b) {
            std::size_t w = offset[b];
            for (std::size_t slot = b * per; slot < std::min(n, (b + 1) * per); ++slot)
                if (open(slot) && (keys_[slot] >> 48) <= bucket) cand[w++] = keys_[slot];
        });
        tbb::parallel_sort(cand.begin(), cand.end());  // a strict order (ties broken by the slot): deterministic
        std::fill(taken.begin(), taken.end(), 0);
        for (const std::uint64_t key : cand) {
            const auto slot = std::uint32_t(key & 0xffffffffu);
            const Tri& t = tris_[slot / 3];
            const std::uint32_t ends[2] = {t[slot % 3], t[(slot % 3 + 1) % 3]};
            if (taken[ends[0]] || taken[ends[1]]) continue;
            selected.push_back(slot);
            for (const std::uint32_t v : ends)
                for (const std::uint32_t f : vf_[v])
                    if (alive_f_[f])
                        for (const std::uint32_t w : tris_[f]) taken[w] = 1;
        }
    }

    /// Collapses the edge in `slot` if the checks allow it: the merged vertex's quadric error as a
    /// distance, or -1 (the edge marked refused) if they do not.
    double try_collapse(std::uint32_t slot, Scratch& sc) {
        const std::size_t f = slot / 3;
        const int k = int(slot % 3);
        std::uint32_t keep = tris_[f][k], gone = tris_[f][(k + 1) % 3];
        const Vec3d x(place_[slot].x);
        // keep the endpoint nearer to x (a locked one is x itself): its attributes are closer
        if (locked_[gone] || (!locked_[keep] && squared_norm(pos_[gone] - x) < squared_norm(pos_[keep] - x)))
            std::swap(keep, gone);
        if (!allowed(keep, gone, x, sc)) {
            state_[slot] = kRefused;
            return -1.0;
        }
        const double w = q_[keep].w + q_[gone].w;
        collapse(keep, gone, x, sc);
        dirty_[keep] = 1;
        // The edges at the merged vertex and its neighbours may pass the checks now. Two collapses of a
        // pass can share a neighbour: the flag is set atomically.
        for (const std::uint32_t f : faces_of(keep))
            for (const std::uint32_t v : tris_[f])
                std::atomic_ref<std::uint8_t>(changed_[v]).store(1, std::memory_order_relaxed);
        return std::sqrt(double(place_[slot].error) / std::max(w, 1e-300));
    }

    /// Where the merged vertex of edge (a, b) goes, and its quadric error there.
    double placement(std::uint32_t a, std::uint32_t b, Vec3d& x) const {
        Quadric q = q_[a];
        q += q_[b];
        if (locked_[a]) {
            x = pos_[a];
            return q(x);
        }
        if (locked_[b]) {
            x = pos_[b];
            return q(x);
        }
        const Vec3d mid = (pos_[a] + pos_[b]) * 0.5;
        Vec3d opt;
        // Keep the optimum near the edge: far from it, the quadric's planes no longer describe the
        // surface (nearly parallel planes of a thin part put it far away).
        const bool solved = opt_.tangent_planes ? q.truncated_minimiser_near(mid, kTruncation, opt)
                                                : q.minimiser_near(mid, kRegularisation, opt);
        const bool near = solved && squared_norm(opt - mid) <= squared_norm(pos_[a] - pos_[b]);
        const Vec3d cand[4] = {pos_[a], pos_[b], mid, opt};
        double best = q(cand[0]);
        x = cand[0];
        for (int k = 1; k < (near ? 4 : 3); ++k) {
            const double e = q(cand[k]);
            if (e < best) {
                best = e;
                x = cand[k];
            }
        }
        return best;
    }

    /// The candidate key of the collapse of edge (a, b) in `slot`, its placement stored in place_[slot].
    std::uint64_t cost(std::uint32_t a, std::uint32_t b, std::size_t slot) {
        Vec3d x;
        const double error = placement(a, b, x);
        // Positions stay floats (they are written back as such), so the costed placement is the one made.
        const Vec3f xf(x);
        place_[slot] = {xf, float(error)};
        // Among collapses of equal error (a flat patch: all zero) the shorter edge first, so that a
        // flat region is decimated evenly instead of into fans of slivers around a few vertices.
        const double shape = kLengthWeight * (q_[a].w + q_[b].w) * squared_norm(pos_[a] - pos_[b]);
        const float c = float(error + shape);
        std::uint32_t bits;
        std::memcpy(&bits, &c, sizeof bits);
        return std::uint64_t(bits) << 32 | std::uint64_t(slot);
    }

    /// The alive faces of v (purging dead ones from its list).
    const FaceList& faces_of(std::uint32_t v) {
        FaceList& l = vf_[v];
        l.remove_if([&](std::uint32_t f) { return !alive_f_[f]; });
        return l;
    }

    static void neighbours(const FaceList& faces, const std::vector<Tri>& tris, std::uint32_t v,
                           std::vector<std::uint32_t>& out) {
        out.clear();
        for (std::uint32_t f : faces)
            for (int k = 0; k < 3; ++k)
                if (tris[f][k] != v) out.push_back(tris[f][k]);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

    /// Whether collapsing `gone` into `keep` at x keeps the mesh manifold and unfolded.
    bool allowed(std::uint32_t keep, std::uint32_t gone, const Vec3d& x, Scratch& sc) {
        const auto& fk = faces_of(keep);
        const auto& fg = faces_of(gone);
        sc.shared.clear();
        for (std::uint32_t f : fg) {
            const Tri& t = tris_[f];
            if (t[0] == keep || t[1] == keep || t[2] == keep) sc.shared.push_back(f);
        }
        if (sc.shared.size() != 2) return false;
        // Link condition: the common neighbours of the two ends are exactly the far corners of the
        // two faces on the edge.
        neighbours(fk, tris_, keep, sc.nk);
        neighbours(fg, tris_, gone, sc.ng);
        sc.common.clear();
        std::set_intersection(sc.nk.begin(), sc.nk.end(), sc.ng.begin(), sc.ng.end(), std::back_inserter(sc.common));
        std::uint32_t far[2];
        for (int s = 0; s < 2; ++s) {
            const Tri& t = tris_[sc.shared[std::size_t(s)]];
            far[s] = t[0] != keep && t[0] != gone ? t[0] : (t[1] != keep && t[1] != gone ? t[1] : t[2]);
        }
        if (far[0] == far[1] || sc.common.size() != 2) return false;
        if (!((sc.common[0] == far[0] && sc.common[1] == far[1]) || (sc.common[0] == far[1] && sc.common[1] == far[0])))
            return false;
        // the merged vertex's neighbours, (N(keep) ∪ N(gone)) less keep and gone: at least 3
        if (sc.nk.size() + sc.ng.size() < 7) return false;
        // Faces that stay: no fold, no degenerate or much worse shape.
        sc.fan.clear();
        for (int side = 0; side < 2; ++side)
            for (std::uint32_t f : side ? fg : fk) {
                const Tri& t = tris_[f];
                const bool has_k = t[0] == keep || t[1] == keep || t[2] == keep;
                const bool has_g = t[0] == gone || t[1] == gone || t[2] == gone;
                if (has_k && has_g) continue;
                Vec3d p[3], q[3];
                for (int k = 0; k < 3; ++k) {
                    p[k] = pos_[t[k]];
                    q[k] = t[k] == keep || t[k] == gone ? x : p[k];
                }
                Vec3d n0, n1;
                const double q0 = quality(p[0], p[1], p[2], &n0);
                const double q1 = quality(q[0], q[1], q[2], &n1);
                const double l0 = norm(n0), l1 = norm(n1);
                if (!(l1 > 0)) return false;
                if (l0 > 0 && dot(n0, n1) < cos_max_ * l0 * l1) return false;
                std::uint32_t other[2], n = 0;
                for (int k = 0; k < 3; ++k)
                    if (t[k] != keep && t[k] != gone) other[n++] = t[k];
                sc.fan.push_back({other[0], other[1], side, l0 > 0 ? n0 / l0 : Vec3d{}, n1 / l1});
                if (q1 < opt_.min_quality && q1 < q0) return false;
                if (!normal_.empty()) {  // the turn from the surface's normals at the corners: bounded, or no worse
                    double c0 = 1, c1 = 1;
                    for (int k = 0; k < 3; ++k) {
                        const Vec3d& n = normal_[t[k] == gone ? keep : t[k]];
                        c1 = std::min(c1, dot(n1, n) / l1);
                        if (l0 > 0) c0 = std::min(c0, dot(n0, normal_[t[k]]) / l0);
                    }
                    if (c1 < cos_deviation_ && c1 < c0) return false;
                }
            }
        // No new sharp fold: two faces of the merged vertex that share an edge (each turned within
        // max_normal_change_deg, together up to twice that) meet at an inner angle of kMinFoldDeg or more, or at no
        // sharper angle than the sharpest two of its faces met before. A fold a few degrees wide is a surface
        // doubling back on itself: tetrahedra there are slivers.
        double before = 1, after = 1;
        for (std::size_t i = 0; i < sc.fan.size(); ++i)
            for (std::size_t j = i + 1; j < sc.fan.size(); ++j) {
                const auto& p = sc.fan[i];
                const auto& q = sc.fan[j];
                if (p.a != q.a && p.a != q.b && p.b != q.a && p.b != q.b) continue;  // no shared edge at x
                after = std::min(after, dot(p.after, q.after));
                if (p.side == q.side) before = std::min(before, dot(p.before, q.before));  // neighbours before too
            }
        if (after < kCosFold && after < before) return false;
        return true;
    }

    void collapse(std::uint32_t keep, std::uint32_t gone, const Vec3d& x, const Scratch& sc) {
        for (std::uint32_t f : sc.shared) alive_f_[f] = 0;
        for (std::uint32_t f : vf_[gone]) {
            if (!alive_f_[f]) continue;
            for (int k = 0; k < 3; ++k)
                if (tris_[f][k] == gone) tris_[f][k] = keep;
            vf_[keep].push_back(f);
        }
        vf_[gone].reset();
        pos_[keep] = x;
        q_[keep] += q_[gone];
    }

    /// Drops the dead faces from tris_ and rebuilds the vertices' face lists (same order of faces).
    void compact_faces() {
        std::size_t w = 0;
        const bool costed = keys_.size() == 3 * tris_.size();
        for (std::size_t f = 0; f < tris_.size(); ++f)
            if (alive_f_[f]) {
                if (costed)  // the slots move with their faces, their keys renumbered
                    for (std::size_t k = 0; k < 3; ++k) {
                        const std::uint64_t key = keys_[3 * f + k];
                        keys_[3 * w + k] =
                            key == kNoCandidate ? key : (key & ~std::uint64_t(0xffffffffu)) | (3 * w + k);
                        place_[3 * w + k] = place_[3 * f + k];
                        state_[3 * w + k] = state_[3 * f + k];
                    }
                tris_[w++] = tris_[f];
            }
        tris_.resize(w);
        if (costed) {
            keys_.resize(3 * w);
            place_.resize(3 * w);
            state_.resize(3 * w);
        }
        alive_f_.assign(w, 1);
        for (auto& l : vf_) l.clear();
        for (std::uint32_t f = 0; f < w; ++f)
            for (int k = 0; k < 3; ++k) vf_[tris_[f][k]].push_back(f);
    }

    void write_back() {
        for (std::size_t v = 0; v < pos_.size(); ++v) m_.positions[v] = Vec3f(pos_[v]);
        m_.triangles.clear();
        for (std::size_t f = 0; f < tris_.size(); ++f)
            if (alive_f_[f]) m_.triangles.push_back(tris_[f]);
        remove_unreferenced_vertices(m_);
    }

    Mesh& m_;
    QemOptions opt_;
    std::vector<Vec3d> pos_;
    std::vector<Quadric> q_;
    std::vector<FaceList> vf_;
    std::vector<std::uint8_t> locked_, alive_f_;
    std::vector<Tri> tris_;
    std::size_t faces_ = 0;
    double cos_max_ = 0.5;
    double cos_deviation_ = -1.0;  ///< max_normal_deviation_deg's cosine
    std::vector<Vec3d> normal_;    ///< unit surface normal per vertex (m.normals), when that bound is on
    double max_error2_ = 0.0;
    std::vector<std::uint64_t> keys_;          ///< per slot (3 per face): the candidate key, or kNoCandidate
    std::vector<Placement> place_;             ///< per slot: the costed placement
    mutable std::vector<std::uint32_t> hist_;  ///< select's histograms
    std::vector<std::uint8_t> state_;          ///< per slot: kOpen, kRefused or kOverBound
    std::vector<std::uint8_t> dirty_;          ///< per vertex: moved or merged since its edges were costed
    std::vector<std::uint8_t> changed_;        ///< per vertex: its neighbourhood changed since the last costing
};

}  // namespace

std::size_t unfold_by_flips(Mesh& m, double min_inner_deg) {
    const double cos_fold = -std::cos(min_inner_deg * std::numbers::pi / 180.0);
    auto& T = m.triangles;
    const auto key = [](std::uint32_t a, std::uint32_t b) {
        return a < b ? std::uint64_t(a) << 32 | b : std::uint64_t(b) << 32 | a;
    };
    // each edge's faces (two on a manifold edge; others are left alone)
    std::unordered_map<std::uint64_t, std::array<std::uint32_t, 3>> faces;  // [0], [1], count
    faces.reserve(T.size() * 2);
    for (std::uint32_t f = 0; f < T.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            auto& e = faces[key(T[f][k], T[f][(k + 1) % 3])];
            if (e[2] < 2) e[e[2]] = f;
            ++e[2];
        }
    const auto normal = [&](const Tri& t) {
        const Vec3d n = cross(Vec3d(m.positions[t[1]]) - Vec3d(m.positions[t[0]]),
                              Vec3d(m.positions[t[2]]) - Vec3d(m.positions[t[0]]));
        const double l = norm(n);
        return l > 0 ? n / l : Vec3d{};
    };
    // the cosine between a face (as t) and the other face on its edge (u, v)
    const auto across = [&](const Tri& t, std::uint32_t self, std::uint32_t u, std::uint32_t v, std::uint32_t skip) {
        const auto it = faces.find(key(u, v));
        if (it == faces.end() || it->second[2] != 2) return 1.0;
        const std::uint32_t o = it->second[0] == self || it->second[0] == skip ? it->second[1] : it->second[0];
        if (o == self || o == skip) return 1.0;
        return dot(normal(t), normal(T[o]));
    };
    std::size_t flips = 0;
    for (int pass = 0; pass < 8; ++pass) {
        std::size_t made = 0;
        for (std::uint32_t f = 0; f < T.size(); ++f)
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t a = T[f][k], b = T[f][(k + 1) % 3], c = T[f][(k + 2) % 3];
                const auto it = faces.find(key(a, b));
                if (it == faces.end() || it->second[2] != 2) continue;
                const std::uint32_t g = it->second[0] == f ? it->second[1] : it->second[0];
                if (dot(normal(T[f]), normal(T[g])) >= cos_fold) continue;
                std::uint32_t d =
                    T[g][0] != a && T[g][0] != b ? T[g][0] : (T[g][1] != a && T[g][1] != b ? T[g][1] : T[g][2]);
                if (d == c || faces.count(key(c, d))) continue;
                const Tri f1{c, a, d}, g1{d, b, c};
                const Vec3d n1 = normal(f1), n2 = normal(g1);
                if (norm(n1) == 0 || norm(n2) == 0) continue;
                // the sharpest angle at the five edges, before and after
                const double before =
                    std::min({dot(normal(T[f]), normal(T[g])), across(T[f], f, b, c, g), across(T[f], f, c, a, g),
                              across(T[g], g, a, d, f), across(T[g], g, d, b, f)});
                const double after = std::min({dot(n1, n2), across(f1, f, c, a, g), across(f1, g, a, d, f),
                                               across(g1, g, d, b, f), across(g1, f, b, c, g)});
                if (!(after > before)) continue;
                faces.erase(key(a, b));
                faces[key(c, d)] = {f, g, 2};
                for (auto& x : faces[key(a, d)]) x = x == g ? f : x;
                for (auto& x : faces[key(b, c)]) x = x == f ? g : x;
                T[f] = f1;
                T[g] = g1;
                ++made;
                break;  // f changed
            }
        flips += made;
        if (made == 0) break;
    }
    return flips;
}

QemReport decimate_mesh_qem(Mesh& m, const QemOptions& opt) {
    const auto t0 = std::chrono::steady_clock::now();
    check_mesh(m, "decimate_mesh");
    if (m.triangles.empty()) throw InvalidInput("decimate_mesh: empty mesh (no triangles)");
    if (m.triangles.size() >= (std::size_t(1) << 32) / 3)  // an edge slot is numbered in 32 bits
        throw InvalidInput("decimate_mesh: too many faces (" + std::to_string(m.triangles.size()) + "), at most " +
                           std::to_string((std::size_t(1) << 32) / 3 - 1));
    if (!(opt.max_error >= 0) || !std::isfinite(opt.max_error))
        throw InvalidInput("decimate_mesh: max_error must be finite and >= 0, got " + std::to_string(opt.max_error));
    if (opt.target_faces < 4 && !(opt.target_faces == 0 && opt.max_error > 0))
        throw InvalidInput("decimate_mesh: target_faces must be >= 4 (or 0 with max_error > 0), got " +
                           std::to_string(opt.target_faces));
    if (opt.tangent_planes && m.normals.size() != m.positions.size())
        throw InvalidInput("decimate_mesh: tangent_planes needs a normal per vertex (m.normals)");
    if (!(opt.max_normal_change_deg > 0 && opt.max_normal_change_deg <= 180))
        throw InvalidInput("decimate_mesh: max_normal_change_deg must be in (0, 180], got " +
                           std::to_string(opt.max_normal_change_deg));
    if (!(opt.max_normal_deviation_deg >= 0 && opt.max_normal_deviation_deg <= 180))
        throw InvalidInput("decimate_mesh: max_normal_deviation_deg must be in [0, 180], got " +
                           std::to_string(opt.max_normal_deviation_deg));
    if (opt.max_normal_deviation_deg > 0 && m.normals.size() != m.positions.size())
        throw InvalidInput("decimate_mesh: max_normal_deviation_deg needs a normal per vertex (m.normals)");
    if (!(opt.min_quality >= 0 && opt.min_quality < 1))
        throw InvalidInput("decimate_mesh: min_quality must be in [0, 1), got " + std::to_string(opt.min_quality));
    QemReport rep = QemDecimation(m, opt).run();
    rep.folds_flipped = unfold_by_flips(m, kMinFoldDeg);
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return rep;
}

}  // namespace normalflow
