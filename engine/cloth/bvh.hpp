#pragma once
// Axis-aligned boxes and a bounding-volume hierarchy over them (median split on
// the longest axis, four boxes per leaf): the broad phase of the exact
// self-intersection count and of the self-contact. Internal to engine/cloth.
#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace drape::cloth::detail {

struct Box {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
    void add(const Box& b)
    {
        lo = lo.cwiseMin(b.lo);
        hi = hi.cwiseMax(b.hi);
    }
    void add(const Eigen::Vector3d& p)
    {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    void inflate(double r)
    {
        lo.array() -= r;
        hi.array() += r;
    }
    bool overlaps(const Box& b) const { return (lo.array() <= b.hi.array()).all() && (b.lo.array() <= hi.array()).all(); }
};

/// A hierarchy over a set of boxes (owned). Pairs are reported by index into
/// the boxes it was built from, in a deterministic order.
class Bvh {
public:
    explicit Bvh(std::vector<Box> boxes) : m_boxes(std::move(boxes)), m_order(m_boxes.size())
    {
        std::iota(m_order.begin(), m_order.end(), 0);
        if (!m_boxes.empty()) build(0, static_cast<int>(m_boxes.size()));
    }
    const std::vector<Box>& boxes() const { return m_boxes; }
    /// New boxes for the same items, the tree kept (children are built after
    /// their parents, so one backward sweep updates every node). A tree built on
    /// a cloth's rest shape groups material neighbours, which stay spatial
    /// neighbours as the cloth moves: refitting it is what cloth simulators do
    /// instead of rebuilding it every step.
    void refit(std::vector<Box> boxes)
    {
        m_boxes = std::move(boxes);
        for (int id = static_cast<int>(m_nodes.size()) - 1; id >= 0; --id) {
            Node& a = m_nodes[static_cast<std::size_t>(id)];
            Box b;
            if (a.left < 0) {
                for (int i = a.first; i < a.first + a.count; ++i) b.add(box(item(i)));
            } else {
                b = node(a.left).box;
                b.add(node(a.right).box);
            }
            a.box = b;
        }
    }
    std::size_t size() const { return m_boxes.size(); }
    /// f(i, j) for every pair i != j of overlapping boxes (each pair once).
    template <class F>
    void self_pairs(F&& f) const
    {
        if (!m_nodes.empty()) self(0, f);
    }
    /// f(i) for every box that overlaps `b`.
    template <class F>
    void query(const Box& b, F&& f) const
    {
        if (!m_nodes.empty()) query(0, b, f);
    }

private:
    struct Node {
        Box box;
        int first = 0, count = 0; ///< leaf: range in m_order
        int left = -1, right = -1;
    };
    const Box& box(int i) const { return m_boxes[static_cast<std::size_t>(i)]; }
    int item(int k) const { return m_order[static_cast<std::size_t>(k)]; }
    const Node& node(int n) const { return m_nodes[static_cast<std::size_t>(n)]; }
    int build(int first, int count)
    {
        const int id = static_cast<int>(m_nodes.size());
        m_nodes.push_back({});
        Box b;
        for (int i = first; i < first + count; ++i) b.add(box(item(i)));
        m_nodes[static_cast<std::size_t>(id)].box = b;
        if (count <= 4) {
            m_nodes[static_cast<std::size_t>(id)].first = first;
            m_nodes[static_cast<std::size_t>(id)].count = count;
            return id;
        }
        int axis = 0;
        (b.hi - b.lo).maxCoeff(&axis);
        const int mid = first + count / 2;
        std::nth_element(m_order.begin() + first, m_order.begin() + mid, m_order.begin() + first + count, [&](int x, int y) {
            const Box& bx = box(x);
            const Box& by = box(y);
            return bx.lo[axis] + bx.hi[axis] < by.lo[axis] + by.hi[axis];
        });
        const int l = build(first, mid - first);
        const int r = build(mid, first + count - mid);
        m_nodes[static_cast<std::size_t>(id)].left = l;
        m_nodes[static_cast<std::size_t>(id)].right = r;
        return id;
    }
    template <class F>
    void self(int n, F& f) const
    {
        const Node& a = node(n);
        if (a.left < 0) {
            for (int i = a.first; i < a.first + a.count; ++i)
                for (int j = i + 1; j < a.first + a.count; ++j) leaf_pair(item(i), item(j), f);
            return;
        }
        self(a.left, f);
        self(a.right, f);
        cross(a.left, a.right, f);
    }
    template <class F>
    void cross(int na, int nb, F& f) const
    {
        const Node& a = node(na);
        const Node& b = node(nb);
        if (!a.box.overlaps(b.box)) return;
        if (a.left < 0 && b.left < 0) {
            for (int i = a.first; i < a.first + a.count; ++i)
                for (int j = b.first; j < b.first + b.count; ++j) leaf_pair(item(i), item(j), f);
            return;
        }
        // Split the larger node (or the one that can be split).
        const bool split_a = b.left < 0 || (a.left >= 0 && (a.box.hi - a.box.lo).squaredNorm() >= (b.box.hi - b.box.lo).squaredNorm());
        if (split_a) {
            cross(a.left, nb, f);
            cross(a.right, nb, f);
        } else {
            cross(na, b.left, f);
            cross(na, b.right, f);
        }
    }
    template <class F>
    void leaf_pair(int i, int j, F& f) const
    {
        if (box(i).overlaps(box(j))) f(i, j);
    }
    template <class F>
    void query(int n, const Box& b, F& f) const
    {
        const Node& a = node(n);
        if (!a.box.overlaps(b)) return;
        if (a.left < 0) {
            for (int i = a.first; i < a.first + a.count; ++i)
                if (box(item(i)).overlaps(b)) f(item(i));
            return;
        }
        query(a.left, b, f);
        query(a.right, b, f);
    }
    std::vector<Box> m_boxes;
    std::vector<int> m_order;
    std::vector<Node> m_nodes;
};

} // namespace drape::cloth::detail
