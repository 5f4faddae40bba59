#include "fit/face_filter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/errors.h"
#include "fit/weld.h"
#include "metrics/noise.h"

namespace normalflow {

namespace {

template <class F>
void parallel(std::size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
}

/// Compressed rows: row i is items[start[i] .. start[i + 1]).
struct Rows {
    std::vector<std::uint32_t> start, items;
    std::size_t size(std::size_t i) const { return start[i + 1] - start[i]; }
    const std::uint32_t* begin(std::size_t i) const { return items.data() + start[i]; }
    const std::uint32_t* end(std::size_t i) const { return items.data() + start[i + 1]; }
};

}  // namespace

const char* to_string(PatchSaliency s) {
    switch (s) {
        case PatchSaliency::Off: return "off";
        case PatchSaliency::On: return "on";
        case PatchSaliency::Chosen: return "chosen";
    }
    return "?";
}

namespace {

/// The rounds run with options a (on a copy of m) and with b (on m), and the run of the lower risk estimate kept: m,
/// the filtered normals and the report are its (b's where the two are equal).
FaceFilterReport keep_lower_risk(Mesh& m, const FaceFilterOptions& a, const FaceFilterOptions& b,
                                 const std::vector<Vec3d>* guidance, const std::vector<char>* held,
                                 std::vector<Vec3d>* filtered_normals) {
    Mesh copy = m;
    std::vector<Vec3d> normals_a;
    const FaceFilterReport rep_a = filter_faces(copy, a, guidance, held, filtered_normals ? &normals_a : nullptr);
    const FaceFilterReport rep_b = filter_faces(m, b, guidance, held, filtered_normals);
    if (!(rep_a.estimated_error < rep_b.estimated_error)) return rep_b;
    m.positions = std::move(copy.positions);
    if (filtered_normals) *filtered_normals = std::move(normals_a);
    return rep_a;
}

}  // namespace

const char* to_string(RangeWeight r) {
    switch (r) {
        case RangeWeight::Guided: return "guided";
        case RangeWeight::None: return "none";
        case RangeWeight::Chosen: return "chosen";
    }
    return "?";
}

FaceFilterReport filter_faces(Mesh& m, const FaceFilterOptions& o, const std::vector<Vec3d>* guidance,
                              const std::vector<char>* held, std::vector<Vec3d>* filtered_normals) {
    if (o.normal_steps < 0 || o.vertex_steps < 0 || o.rings < 1 || !(o.sigma_r > 0) || !(o.sigma_s > 0) ||
        !std::isfinite(o.sigma_r) || !std::isfinite(o.sigma_s) || !(o.own_patch_bias > 0 && o.own_patch_bias <= 1) ||
        !(o.stop_displacement >= 0) || !std::isfinite(o.stop_displacement) || !(o.stop_noise >= 0) ||
        !std::isfinite(o.stop_noise) || (o.stop_displacement > 0 && o.stop_noise > 0))
        throw InvalidInput(
            "filter_faces: normal_steps and vertex_steps must be >= 0, rings >= 1, sigma_r and sigma_s finite and > 0, "
            "own_patch_bias in (0, 1], stop_displacement and stop_noise finite and >= 0, not both > 0");
    check_mesh(m, "filter_faces");
    if (o.range == RangeWeight::Chosen) {
        // The weight on the guidance and none, and the one whose rounds the risk estimate finds of least error
        FaceFilterOptions guided = o, none = o;
        guided.range = RangeWeight::Guided;
        none.range = RangeWeight::None;
        if (!(o.stop_noise > 0)) return filter_faces(m, guided, guidance, held, filtered_normals);
        return keep_lower_risk(m, none, guided, guidance, held, filtered_normals);
    }
    if (o.saliency == PatchSaliency::Chosen) {
        // Both measures of a patch's consistency, and the one whose rounds the risk estimate finds of least error
        if (!(o.stop_noise > 0) || !o.patch_guidance || o.range == RangeWeight::None) {  // no patch to measure
            FaceFilterOptions plain = o;
            plain.saliency = PatchSaliency::Off;
            return filter_faces(m, plain, guidance, held, filtered_normals);
        }
        FaceFilterOptions off = o, on = o;
        off.saliency = PatchSaliency::Off;
        on.saliency = PatchSaliency::On;
        return keep_lower_risk(m, on, off, guidance, held, filtered_normals);
    }
    const std::size_t nf = m.triangles.size();
    if (guidance && guidance->size() != nf)
        throw InvalidInput("filter_faces: " + std::to_string(guidance->size()) + " guidance normals for " +
                           std::to_string(nf) + " faces");
    if (held && held->size() != m.positions.size())
        throw InvalidInput("filter_faces: " + std::to_string(held->size()) + " held flags for " +
                           std::to_string(m.positions.size()) + " positions");
    FaceFilterReport rep;
    std::vector<std::uint32_t> group;
    const std::size_t n = detail::weld(m, group);
    std::vector<Vec3d> x(n);
    std::vector<char> fixed(n, 0);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        x[group[i]] = Vec3d(m.positions[i]);
        if (held && (*held)[i]) fixed[group[i]] = 1;
    }
    {
        const std::vector<char> on = detail::boundary_vertices(m, group, n);
        for (std::size_t i = 0; i < n; ++i) fixed[i] = fixed[i] || on[i];
    }
    // the welded faces that have three distinct vertices
    std::vector<std::array<std::uint32_t, 3>> tri(nf);
    std::vector<char> live(nf, 0);
    for (std::size_t f = 0; f < nf; ++f) {
        const Tri& t = m.triangles[f];
        tri[f] = {group[t[0]], group[t[1]], group[t[2]]};
        live[f] = tri[f][0] != tri[f][1] && tri[f][1] != tri[f][2] && tri[f][0] != tri[f][2];
        rep.faces += std::size_t(live[f]);
    }
    // vertex → faces
    Rows vf;
    vf.start.assign(n + 1, 0);
    for (std::size_t f = 0; f < nf; ++f)
        if (live[f])
            for (std::uint32_t a : tri[f]) ++vf.start[a + 1];
    for (std::size_t i = 0; i < n; ++i) vf.start[i + 1] += vf.start[i];
    vf.items.resize(vf.start[n]);
    {
        std::vector<std::uint32_t> fill(vf.start.begin(), vf.start.end() - 1);
        for (std::size_t f = 0; f < nf; ++f)
            if (live[f])
                for (std::uint32_t a : tri[f]) vf.items[fill[a]++] = std::uint32_t(f);
    }
    // face → the faces of its vertex ring (itself included), sorted; then `rings` rings of those
    const auto ring_of = [&](std::size_t f, std::vector<std::uint32_t>& out) {
        out.clear();
        for (std::uint32_t a : tri[f]) out.insert(out.end(), vf.begin(a), vf.end(a));
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    };
    const auto build_rows = [&](int rings) {
        std::vector<std::vector<std::uint32_t>> rows(nf);
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            std::vector<std::uint32_t> cur, tmp, next;
            ring_of(f, cur);
            for (int r = 1; r < rings; ++r) {
                next = cur;
                for (std::uint32_t k : cur) {
                    ring_of(k, tmp);
                    next.insert(next.end(), tmp.begin(), tmp.end());
                }
                std::sort(next.begin(), next.end());
                next.erase(std::unique(next.begin(), next.end()), next.end());
                cur.swap(next);
            }
            rows[f] = std::move(cur);
        });
        Rows out;
        out.start.assign(nf + 1, 0);
        for (std::size_t f = 0; f < nf; ++f) out.start[f + 1] = out.start[f] + std::uint32_t(rows[f].size());
        out.items.resize(out.start[nf]);
        for (std::size_t f = 0; f < nf; ++f)
            std::copy(rows[f].begin(), rows[f].end(), out.items.begin() + out.start[f]);
        return out;
    };
    const Rows patch = build_rows(1);
    const Rows hood = o.rings == 1 ? patch : build_rows(o.rings);
    const bool weighed = o.range != RangeWeight::None;  // the guidance's weight (Chosen was resolved above)
    const bool salient = weighed && o.patch_guidance && o.saliency == PatchSaliency::On;
    rep.salient = salient;
    rep.guided = weighed;
    // face → the face across each of its edges (none where the edge is not shared by exactly two), for the saliency
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::array<std::uint32_t, 3>> across(salient ? nf : 0, {kNone, kNone, kNone});
    if (salient) {
        std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, int>> es;
        for (std::size_t f = 0; f < nf; ++f)
            if (live[f])
                for (int e = 0; e < 3; ++e) {
                    const std::uint32_t a = tri[f][std::size_t(e)], b = tri[f][std::size_t((e + 1) % 3)];
                    es.emplace_back(std::min(a, b), std::max(a, b), std::uint32_t(f), e);
                }
        std::sort(es.begin(), es.end());
        for (std::size_t i = 0; i < es.size();) {
            std::size_t j = i;
            while (j < es.size() && std::get<0>(es[j]) == std::get<0>(es[i]) &&
                   std::get<1>(es[j]) == std::get<1>(es[i]))
                ++j;
            if (j - i == 2) {
                across[std::get<2>(es[i])][std::size_t(std::get<3>(es[i]))] = std::get<2>(es[i + 1]);
                across[std::get<2>(es[i + 1])][std::size_t(std::get<3>(es[i + 1]))] = std::get<2>(es[i]);
            }
            i = j;
        }
    }

    // The state one run of the rounds changes: the vertices and what is measured from them. The risk stop runs
    // kRiskProbes perturbed states in step with the first.
    struct State {
        std::vector<Vec3d> x, normal, centre, guide, filtered, base, next, mean;
        std::vector<double> area, spread;
        std::vector<char> revert, turns;
        std::size_t reverted = 0;
    };
    const auto make_state = [&](std::vector<Vec3d> positions) {
        State st;
        st.x = std::move(positions);
        st.normal.resize(nf), st.centre.resize(nf), st.guide.resize(nf), st.filtered.resize(nf), st.base.resize(nf);
        st.mean.resize(nf), st.spread.resize(nf);
        st.next.resize(n);
        st.area.assign(nf, 0.0);
        st.revert.assign(n, 0);
        st.turns.assign(nf, 0);
        return st;
    };
    const auto measure = [&](State& st) {
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            const Vec3d &a = st.x[tri[f][0]], &b = st.x[tri[f][1]], &c = st.x[tri[f][2]];
            const Vec3d cr = cross(b - a, c - a);
            const double len = norm(cr);
            st.area[f] = 0.5 * len;
            st.normal[f] = len > 0 ? cr / len : Vec3d(0, 0, 0);
            st.centre[f] = (a + b + c) / 3.0;
        });
    };
    State cur = make_state(std::move(x));
    measure(cur);
    // σ_s: the mean distance between the centroids of faces that share a vertex
    double spacing = 0.0;
    {
        std::vector<double> per(nf, 0.0);
        std::vector<std::uint32_t> count(nf, 0);
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            for (const std::uint32_t* k = patch.begin(f); k != patch.end(f); ++k)
                if (*k != f) {
                    per[f] += norm(cur.centre[*k] - cur.centre[f]);
                    ++count[f];
                }
        });
        double sum = 0.0;
        std::size_t cnt = 0;
        for (std::size_t f = 0; f < nf; ++f) sum += per[f], cnt += count[f];
        spacing = cnt ? sum / double(cnt) : 0.0;
    }
    const auto write_back = [&](const std::vector<Vec3d>& positions) {
        for (std::size_t i = 0; i < m.positions.size(); ++i) m.positions[i] = Vec3f(positions[group[i]]);
    };
    if (!(spacing > 0) || rep.faces == 0) return rep;
    const double inv_s = 1.0 / (2.0 * std::pow(o.sigma_s * spacing, 2));
    const double inv_r = 1.0 / (2.0 * o.sigma_r * o.sigma_r);

    // One round: the guidance, the joint bilateral filter of the normals, the vertex update.
    const auto round = [&](State& st) {
        // the normals the guidance is built from: the given ones, else the current ones
        parallel(nf, [&](std::size_t f) {
            st.base[f] = st.normal[f];
            if (guidance && norm((*guidance)[f]) > 0.5) st.base[f] = (*guidance)[f];
        });
        if (weighed && o.patch_guidance) {  // (without the weight nothing reads the guidance: none is built)
            // each face's patch: its area-weighted mean base normal and its spread (the largest distance from it);
            // infinite where the mean has no direction
            parallel(nf, [&](std::size_t j) {
                st.spread[j] = std::numeric_limits<double>::infinity();
                if (!live[j]) return;
                Vec3d mean(0, 0, 0);
                for (const std::uint32_t* k = patch.begin(j); k != patch.end(j); ++k)
                    mean = mean + st.base[*k] * st.area[*k];
                const double len = norm(mean);
                if (!(len > 0)) return;
                mean = mean / len;
                st.mean[j] = mean;
                double spread = 0.0;
                for (const std::uint32_t* k = patch.begin(j); k != patch.end(j); ++k)
                    if (st.area[*k] > 0) spread = std::max(spread, norm(st.base[*k] - mean));
                if (salient) {
                    // Zhang et al.'s relative saliency: the largest normal difference across an edge inside the
                    // patch over their sum. Noise spreads its differences over every edge; a crease puts them on a
                    // few.
                    double most = 0.0, sum = 0.0;
                    for (const std::uint32_t* k = patch.begin(j); k != patch.end(j); ++k)
                        for (const std::uint32_t nb : across[*k])
                            if (nb != kNone && nb > *k && std::binary_search(patch.begin(j), patch.end(j), nb)) {
                                const double d = norm(st.base[*k] - st.base[nb]);
                                most = std::max(most, d);
                                sum += d;
                            }
                    spread *= most / (1e-9 + sum);
                }
                st.spread[j] = spread;
            });
            parallel(nf, [&](std::size_t f) {
                if (!live[f]) return;
                // the face's own patch first: another one wins only if clearly more consistent
                Vec3d chosen = st.base[f];
                double best = std::numeric_limits<double>::infinity();
                if (const double own = st.spread[f]; own < best) {
                    best = own * o.own_patch_bias;
                    chosen = st.mean[f];
                }
                for (const std::uint32_t* j = patch.begin(f); j != patch.end(f); ++j)
                    if (*j != f && st.spread[*j] < best) {
                        best = st.spread[*j];
                        chosen = st.mean[*j];
                    }
                st.guide[f] = chosen;
            });
        } else if (weighed) {
            st.guide = st.base;
        }
        // joint bilateral filter of the normals
        parallel(nf, [&](std::size_t f) {
            if (!live[f]) return;
            Vec3d sum(0, 0, 0);
            for (const std::uint32_t* k = hood.begin(f); k != hood.end(f); ++k) {
                const Vec3d d = st.centre[*k] - st.centre[f];
                double range = 0.0;
                if (weighed) {
                    const Vec3d g = st.guide[*k] - st.guide[f];
                    range = dot(g, g) * inv_r;
                }
                sum = sum + st.normal[*k] * (st.area[*k] * std::exp(-dot(d, d) * inv_s - range));
            }
            const double len = norm(sum);
            st.filtered[f] = len > 0 ? sum / len : st.normal[f];
        });
        // vertex update toward the filtered normals; no face turns over
        for (int s = 0; s < o.vertex_steps; ++s) {
            parallel(n, [&](std::size_t i) {
                st.next[i] = st.x[i];
                if (fixed[i] || vf.size(i) == 0) return;
                Vec3d sum(0, 0, 0);
                for (const std::uint32_t* k = vf.begin(i); k != vf.end(i); ++k) {
                    const auto& t = tri[*k];
                    const Vec3d c = (st.x[t[0]] + st.x[t[1]] + st.x[t[2]]) / 3.0;
                    sum = sum + st.filtered[*k] * dot(st.filtered[*k], c - st.x[i]);
                }
                st.next[i] = st.x[i] + sum / double(vf.size(i));
            });
            for (;;) {  // each pass undoes at least one move, so this ends
                parallel(nf, [&](std::size_t f) {
                    st.turns[f] = 0;
                    if (!live[f]) return;
                    const auto& t = tri[f];
                    // against the given guidance where there is one (the volume's side of the surface)
                    const Vec3d& ref = st.base[f];
                    const Vec3d cr = cross(st.next[t[1]] - st.next[t[0]], st.next[t[2]] - st.next[t[0]]);
                    const Vec3d was = cross(st.x[t[1]] - st.x[t[0]], st.x[t[2]] - st.x[t[0]]);
                    // a face already turned is not this move's doing
                    st.turns[f] = (dot(was, ref) > 0 && dot(cr, ref) <= 0) ||
                                  (dot(was, st.filtered[f]) > 0 && dot(cr, st.filtered[f]) <= 0);
                });
                std::fill(st.revert.begin(), st.revert.end(), 0);
                bool any = false;
                for (std::size_t f = 0; f < nf; ++f)
                    if (st.turns[f])
                        for (std::uint32_t a : tri[f])
                            if (st.next[a] != st.x[a]) st.revert[a] = 1, any = true;
                if (!any) break;
                for (std::size_t i = 0; i < n; ++i)
                    if (st.revert[i]) st.next[i] = st.x[i], ++st.reverted;
            }
            st.x.swap(st.next);
        }
        measure(st);
    };

    const std::vector<Vec3d> start = cur.x;
    // the vertices' root-mean-square distance from where they began (a sum in a fixed order: thread-independent)
    const auto rms_displacement = [&](const std::vector<Vec3d>& at) {
        double sum = 0.0;
        for (std::size_t i = 0; i < n; ++i) sum += dot(at[i] - start[i], at[i] - start[i]);
        return std::sqrt(sum / double(n));
    };
    if (o.stop_noise > 0) {
        // Stein's unbiased risk estimate of the vertices' squared error along the steady normals N after k rounds,
        // for noise of deviation σ along them: |r_k|² − nσ² + 2σ² div_k, r_k the vertices' moves along N, div_k the
        // divergence of the rounds, by Monte Carlo (Ramani et al. 2008): kRiskProbes copies of the input, each moved by
        // ε σ b_i N_i (b_i = ±1 at random, a fixed seed), run the same rounds; div_k ≈ mean of Σ b_i (x'_i − x_i)·N_i / εσ.
        std::vector<Vec3d> area_normal(n, Vec3d(0, 0, 0));
        std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
        edges.reserve(3 * nf);
        for (std::size_t f = 0; f < nf; ++f) {
            if (!live[f]) continue;
            for (int e = 0; e < 3; ++e) {
                area_normal[tri[f][std::size_t(e)]] += cur.normal[f] * cur.area[f];
                const std::uint32_t a = tri[f][std::size_t(e)], b = tri[f][std::size_t((e + 1) % 3)];
                edges.emplace_back(std::min(a, b), std::max(a, b));
            }
        }
        std::sort(edges.begin(), edges.end());
        edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
        const std::vector<Vec3d> N = steady_vertex_normals(area_normal, edges);
        const double sigma = o.stop_noise, probe = kRiskProbe * sigma;
        std::mt19937_64 rng(0x5EED5u);
        std::vector<std::vector<double>> sign{std::size_t(kRiskProbes), std::vector<double>(n, 0.0)};
        std::vector<State> perturbed;
        for (auto& sg : sign) {
            for (std::size_t i = 0; i < n; ++i) sg[i] = (rng() >> 63) ? 1.0 : -1.0;
            std::vector<Vec3d> moved = start;
            for (std::size_t i = 0; i < n; ++i) moved[i] += N[i] * (probe * sg[i]);
            perturbed.push_back(make_state(std::move(moved)));
            measure(perturbed.back());
        }
        // The estimate's two parts for the current round: the moves along N (each vertex's), and the divergence.
        // Sums in a fixed order: thread-independent.
        struct Round {
            std::vector<Vec3d> x;   // the vertices
            std::vector<double> r;  // their moves along N
            double divergence = 0.0;
            double risk = 0.0;
        };
        const auto measure_round = [&] {
            Round q;
            q.x = cur.x;
            q.r.resize(n);
            double residual = 0.0;
            for (std::size_t i = 0; i < n; ++i) {
                q.r[i] = dot(cur.x[i] - start[i], N[i]);
                residual += q.r[i] * q.r[i];
            }
            for (std::size_t p = 0; p < perturbed.size(); ++p)
                for (std::size_t i = 0; i < n; ++i)
                    q.divergence += sign[p][i] * dot(perturbed[p].x[i] - cur.x[i], N[i]) / probe;
            q.divergence /= double(perturbed.size());
            q.risk = residual - double(n) * sigma * sigma + 2.0 * sigma * sigma * q.divergence;
            return q;
        };
        Round least = measure_round();      // no round at all: about nσ²
        Round last = least, before, after;  // the round before the current one; those beside the least
        bool has_before = false, has_after = false;
        std::vector<Vec3d> kept_filtered = cur.normal;
        for (int k = 1; k <= o.normal_steps; ++k) {
            round(cur);
            for (State& st : perturbed) round(st);
            ++rep.rounds_run;
            Round now = measure_round();
            if (now.risk < least.risk) {
                before = std::move(last);
                has_before = true;
                least = now;
                has_after = false;
                rep.rounds = k;
                kept_filtered = cur.filtered;
            } else if (k == rep.rounds + 1) {
                after = now;
                has_after = true;
            }
            last = std::move(now);
            if (k - rep.rounds >= kRiskPatience) break;
        }
        // Between the rounds: the blend (1 − a) x_k + a x_j of the least round k with the round j before or after it is an
        // estimator too, linear in the input, and its risk estimate is quadratic in a: |r_k + a (r_j − r_k)|² − nσ² +
        // 2σ² ((1 − a) div_k + a div_j), least at a = −(r_k · (r_j − r_k) + σ² (div_j − div_k)) / |r_j − r_k|². The
        // rounds step the surface in jumps (a statue's first round removes most of its noise); the blend that the
        // estimate prefers, within [0, 1] on either side, is kept where it is lower still and turns no face over
        // against the least round's.
        std::vector<Vec3d> kept = least.x;
        double kept_risk = least.risk;
        const auto blend_toward = [&](const Round& j, double side) {
            double ra = 0.0, aa = 0.0;
            for (std::size_t i = 0; i < n; ++i) {
                const double d = j.r[i] - least.r[i];
                ra += least.r[i] * d;
                aa += d * d;
            }
            if (!(aa > 0.0)) return;
            const double a = std::clamp(-(ra + sigma * sigma * (j.divergence - least.divergence)) / aa, 0.0, 1.0);
            const double r =
                least.risk + 2.0 * a * ra + a * a * aa + 2.0 * sigma * sigma * a * (j.divergence - least.divergence);
            if (!(a > 0.0) || !(r < kept_risk)) return;
            std::vector<Vec3d> x(n);
            for (std::size_t i = 0; i < n; ++i) x[i] = least.x[i] + (j.x[i] - least.x[i]) * a;
            for (std::size_t f = 0; f < nf; ++f) {
                if (!live[f]) continue;
                const auto& t = tri[f];
                const Vec3d was = cross(least.x[t[1]] - least.x[t[0]], least.x[t[2]] - least.x[t[0]]);
                const Vec3d now = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]);
                // a face without area in the round turns nothing over (as a round's own check has it)
                if (dot(was, was) > 0.0 && dot(was, now) <= 0.0) return;
            }
            kept = std::move(x);
            kept_risk = r;
            rep.blend = side * a;
        };
        if (has_before) blend_toward(before, -1.0);
        if (has_after) blend_toward(after, 1.0);
        rep.reverted_moves = cur.reverted;
        rep.estimated_error = std::sqrt(std::max(kept_risk, 0.0) / double(n));
        rep.rms_displacement = rms_displacement(kept);
        write_back(kept);
        if (filtered_normals) *filtered_normals = kept_filtered;
        return rep;
    }
    for (int k = 0; k < o.normal_steps; ++k) {
        if (o.stop_displacement > 0 && rep.rms_displacement >= o.stop_displacement) break;
        round(cur);
        ++rep.rounds;
        rep.rms_displacement = rms_displacement(cur.x);
    }
    rep.rounds_run = rep.rounds;
    rep.reverted_moves = cur.reverted;
    write_back(cur.x);
    if (filtered_normals) *filtered_normals = cur.filtered;
    return rep;
}

}  // namespace normalflow
