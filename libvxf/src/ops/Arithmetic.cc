#include <vxf/ops/Arithmetic.h>

#include "Dispatch.h"

#include <cmath>

namespace vxf::ops {

void arithmetic(openvdb::GridBase& grid, ArithmeticOp op, const openvdb::Vec3d& value)
{
    detail::dispatch(grid, "arithmetic", [&](auto& g) {
        using GridT = std::decay_t<decltype(g)>;
        using ValueT = typename GridT::ValueType;
        const ValueT operand = detail::fromColor<ValueT>(value);
        const auto apply = [&g, &operand](auto&& combine) {
            detail::forEachActiveValue(g, [&](ValueT& v) {
                for (int c = 0; c < detail::channels(v); ++c)
                    detail::ref(v, c) = detail::finite(combine(detail::get(v, c), detail::get(operand, c)));
            });
        };
        switch (op) {
        case ArithmeticOp::Add: apply([](double x, double y) { return x + y; }); break;
        case ArithmeticOp::Sub: apply([](double x, double y) { return x - y; }); break;
        case ArithmeticOp::Mul: apply([](double x, double y) { return x * y; }); break;
        case ArithmeticOp::Div: apply([](double x, double y) { return y == 0.0 ? 0.0 : x / y; }); break;
        case ArithmeticOp::Pow:
            // In float (the grid's precision): twice as fast as double pow.
            apply([](double x, double y) {
                const float fx = float(x), fy = float(y);
                return double(fx < 0.0f ? -std::pow(-fx, fy) : (fx == 0.0f && fy < 0.0f ? 0.0f : std::pow(fx, fy)));
            });
            break;
        }
    });
}

} // namespace vxf::ops
