#include <vxf/ops/Arithmetic.h>

#include "Dispatch.h"

#include <openvdb/tools/ValueTransformer.h>

#include <cmath>

namespace vxf::ops {

void arithmetic(openvdb::GridBase& grid, ArithmeticOp op, const openvdb::Vec3d& value)
{
    detail::dispatch(grid, "arithmetic", [&](auto& g) {
        using GridT = std::decay_t<decltype(g)>;
        using ValueT = typename GridT::ValueType;
        const ValueT operand = detail::fromColor<ValueT>(value);
        openvdb::tools::foreach(g.beginValueOn(), [op, operand](const typename GridT::ValueOnIter& it) {
            ValueT v = *it;
            for (int c = 0; c < detail::channels(v); ++c) {
                const double x = detail::get(v, c), y = detail::get(operand, c);
                double r = x;
                switch (op) {
                case ArithmeticOp::Add: r = x + y; break;
                case ArithmeticOp::Sub: r = x - y; break;
                case ArithmeticOp::Mul: r = x * y; break;
                case ArithmeticOp::Div: r = y == 0.0 ? 0.0 : x / y; break;
                case ArithmeticOp::Pow: r = x < 0.0 ? -std::pow(-x, y) : (x == 0.0 && y < 0.0 ? 0.0 : std::pow(x, y)); break;
                }
                detail::ref(v, c) = detail::finite(r);
            }
            it.setValue(v);
        });
    });
}

} // namespace vxf::ops
