// pliant — device memory for the engine: an owning buffer, and the model's arrays on the device
// (used in place on the CPU, whose memory is the device's; copied once elsewhere).
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "../model.hpp"

namespace pliant {

/// n values of V in the device's memory (zeroed), or a view of host memory the device shares.
template <class V, class Dev>
class DeviceBuffer {
public:
    DeviceBuffer() = default;
    DeviceBuffer(Dev& dev, std::size_t n) : dev_(&dev), n_(n), owned_(true) {
        p_ = static_cast<V*>(dev.allocate(n * sizeof(V)));
    }
    /// The device's copy of host values (a view when the device shares host memory).
    static DeviceBuffer mirror(Dev& dev, const std::vector<V>& host) {
        if constexpr (Dev::kSharesHost) {
            DeviceBuffer b;
            b.dev_ = &dev;
            b.n_ = host.size();
            b.p_ = const_cast<V*>(host.data());
            return b;
        } else {
            DeviceBuffer b(dev, host.size());
            dev.copy_in(b.p_, host.data(), host.size() * sizeof(V));
            return b;
        }
    }
    DeviceBuffer(DeviceBuffer&& o) noexcept { swap(o); }
    DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
        DeviceBuffer t(std::move(o));
        swap(t);
        return *this;
    }
    DeviceBuffer(const DeviceBuffer&) = delete;
    DeviceBuffer& operator=(const DeviceBuffer&) = delete;
    ~DeviceBuffer() {
        if (owned_ && p_) dev_->release(p_);
    }
    V* data() const { return p_; }
    std::size_t size() const { return n_; }
    void upload(const V* host, std::size_t n) { dev_->copy_in(p_, host, n * sizeof(V)); }
    void download(V* host, std::size_t n) const { dev_->copy_out(host, p_, n * sizeof(V)); }
    std::vector<V> to_host() const {
        std::vector<V> h(n_);
        download(h.data(), n_);
        return h;
    }

private:
    void swap(DeviceBuffer& o) noexcept {
        std::swap(dev_, o.dev_);
        std::swap(p_, o.p_);
        std::swap(n_, o.n_);
        std::swap(owned_, o.owned_);
    }
    Dev* dev_ = nullptr;
    V* p_ = nullptr;
    std::size_t n_ = 0;
    bool owned_ = false;
};

/// The model's arrays that the kernels read, on the device.
template <class T, class Dev>
struct ModelBuffers {
    DeviceBuffer<index_t, Dev> elem_nodes, elem_id, block_group, inc_off, inc_idx, inc_slot, pcurve, co, cdof,
        ccurve, cnodes, cbits, pf_off, pf_idx, pnodes, pslot, snodes, sbits, slabel, stris, spair, svtri_off,
        svtri, sedges, stri_edge, edge_off, edge_slot, edge_group, elem_edges, mem_off, mem_idx, mem_nodes,
        mem_kind, mem_nbrs;
    DeviceBuffer<T, Dev> edge_w, elem_grad, elem_vol, mass, inv_mass, relax_mass, relax_inv_mass, free_mask,
        patterns, cval, pedges, pvalue, ptraction, node_vol;
    DeviceBuffer<LoadCurve, Dev> curves;
    DeviceBuffer<double, Dev> tt, tv, X, grid, stri_h, ssheet_h, cskin;

    ModelBuffers() = default;
    ModelBuffers(Dev& d, const Model<T>& m) {
        auto I = [&](const std::vector<index_t>& v) { return DeviceBuffer<index_t, Dev>::mirror(d, v); };
        auto R = [&](const std::vector<T>& v) { return DeviceBuffer<T, Dev>::mirror(d, v); };
        auto D = [&](const std::vector<double>& v) { return DeviceBuffer<double, Dev>::mirror(d, v); };
        elem_nodes = I(m.elem_nodes), elem_id = I(m.elem_id), inc_off = I(m.inc_offsets);
        block_group = I(m.block_group);
        inc_idx = I(m.inc_index), inc_slot = I(m.inc_slot), pcurve = I(m.pattern_curve),
        co = I(m.cons_offsets);
        cdof = I(m.cons_dof), ccurve = I(m.cons_curve), cnodes = I(m.contact_nodes);
        cbits = I(m.contact_bits), cskin = D(m.contact_skin), pf_off = I(m.pface_offsets),
        pf_idx = I(m.pface_index);
        pnodes = I(m.press_nodes), pslot = I(m.press_slot);
        elem_grad = R(m.elem_grad), elem_vol = R(m.elem_vol), mass = R(m.mass), inv_mass = R(m.inv_mass);
        relax_mass = R(m.relax_mass), relax_inv_mass = R(m.relax_inv_mass), free_mask = R(m.free_mask);
        patterns = R(m.load_patterns), cval = R(m.cons_value), pedges = R(m.press_edges);
        pvalue = R(m.press_value), ptraction = R(m.press_traction), node_vol = R(m.node_volume);
        curves = DeviceBuffer<LoadCurve, Dev>::mirror(d, m.curves);
        tt = D(m.table_t), tv = D(m.table_v), X = D(m.X), grid = D(m.tool_grid);
        snodes = I(m.soft_nodes), sbits = I(m.soft_bits), slabel = I(m.soft_label), stris = I(m.soft_tris);
        spair = I(m.soft_pair), stri_h = D(m.soft_tri_h), svtri_off = I(m.soft_vtri_off);
        ssheet_h = D(m.soft_sheet_h);
        svtri = I(m.soft_vtri), sedges = I(m.soft_edges), stri_edge = I(m.soft_tri_edge);
        edge_off = I(m.edge_off), edge_slot = I(m.edge_slot), edge_group = I(m.edge_group);
        elem_edges = I(m.elem_edges), edge_w = R(m.edge_w);
        mem_off = I(m.mem_offsets), mem_idx = I(m.mem_index), mem_nodes = I(m.mem_nodes);
        mem_kind = I(m.mem_kind), mem_nbrs = I(m.mem_nbrs);  // mem_geom, mem_bend: the engine's (scaled)
    }
};

}  // namespace pliant
