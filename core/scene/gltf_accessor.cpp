// Checked accessor reading (see gltf_accessor.h).
#include "core/scene/gltf_accessor.h"

#include "core/common/error.h"

#include <fmt/format.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace modestack::scene {
namespace {

struct AccessorContext {
    const tinygltf::Model& model;
    const std::string& file;
    std::string what;
    int index;

    [[noreturn]] void fail(const std::string& reason) const
    {
        throw bad_input(file, fmt::format("accessor {} ({}): {}", index, what, reason));
    }
};

int components_of(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR:
        return 1;
    case TINYGLTF_TYPE_VEC2:
        return 2;
    case TINYGLTF_TYPE_VEC3:
        return 3;
    case TINYGLTF_TYPE_VEC4:
        return 4;
    case TINYGLTF_TYPE_MAT2:
        return 4;
    case TINYGLTF_TYPE_MAT3:
        return 9;
    case TINYGLTF_TYPE_MAT4:
        return 16;
    default:
        return 0;
    }
}

int component_size(int component_type)
{
    switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return 4;
    default:
        return 0;
    }
}

// One component as double: floats as they are, integers raw or normalised.
double read_component(const unsigned char* p, int component_type, bool normalized)
{
    switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
    }
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        auto v = static_cast<std::int8_t>(*p);
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? *p / 255.0 : *p;
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
    }
    default: {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
    }
    }
}

// The bytes of `count` elements of `element_size` bytes, `stride` apart, starting
// `offset` bytes into buffer view `view_index`; checked against the view and buffer.
const unsigned char* view_data(const AccessorContext& context, int view_index, std::size_t offset,
                               std::size_t count, std::size_t element_size, std::size_t stride)
{
    const auto& model = context.model;
    if (view_index < 0 || static_cast<std::size_t>(view_index) >= model.bufferViews.size())
        context.fail(fmt::format("buffer view {} does not exist", view_index));
    const tinygltf::BufferView& view = model.bufferViews[view_index];
    if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size())
        context.fail(fmt::format("buffer {} does not exist", view.buffer));
    const tinygltf::Buffer& buffer = model.buffers[view.buffer];
    std::size_t needed = count == 0 ? 0 : offset + (count - 1) * stride + element_size;
    if (needed > view.byteLength)
        context.fail(
            fmt::format("needs {} bytes but its buffer view {} has {}", needed, view_index, view.byteLength));
    if (view.byteOffset + view.byteLength > buffer.data.size())
        context.fail(
            fmt::format("buffer view {} ends at byte {} but buffer {} has {} bytes (truncated .bin?)",
                        view_index, view.byteOffset + view.byteLength, view.buffer, buffer.data.size()));
    return buffer.data.data() + view.byteOffset + offset;
}

// Every component of the accessor, as double, `components` per element.
std::vector<double> read_accessor(const AccessorContext& context, int components)
{
    const auto& model = context.model;
    if (context.index < 0 || static_cast<std::size_t>(context.index) >= model.accessors.size())
        context.fail("does not exist");
    const tinygltf::Accessor& accessor = model.accessors[context.index];
    if (components_of(accessor.type) != components)
        context.fail(fmt::format("has {} components per element, expected {}", components_of(accessor.type),
                                 components));
    int size = component_size(accessor.componentType);
    if (size == 0)
        context.fail(fmt::format("unknown component type {}", accessor.componentType));
    std::size_t element_size = static_cast<std::size_t>(size) * components;
    std::vector<double> values(accessor.count * components, 0.0);
    if (accessor.bufferView >= 0) {
        if (static_cast<std::size_t>(accessor.bufferView) >= model.bufferViews.size())
            context.fail(fmt::format("buffer view {} does not exist", accessor.bufferView));
        std::size_t stride = model.bufferViews[accessor.bufferView].byteStride;
        if (stride == 0)
            stride = element_size;
        if (stride < element_size)
            context.fail(
                fmt::format("byte stride {} is smaller than its {}-byte elements", stride, element_size));
        const unsigned char* data = view_data(context, accessor.bufferView, accessor.byteOffset,
                                              accessor.count, element_size, stride);
        for (std::size_t e = 0; e < accessor.count; ++e)
            for (int c = 0; c < components; ++c)
                values[e * components + c] =
                    read_component(data + e * stride + c * size, accessor.componentType, accessor.normalized);
    }
    if (accessor.sparse.isSparse) {
        auto count = static_cast<std::size_t>(std::max(accessor.sparse.count, 0));
        int index_type = accessor.sparse.indices.componentType;
        int index_size = component_size(index_type);
        if (index_size == 0 || index_type == TINYGLTF_COMPONENT_TYPE_FLOAT)
            context.fail("sparse indices have a bad component type");
        const unsigned char* indices =
            view_data(context, accessor.sparse.indices.bufferView, accessor.sparse.indices.byteOffset, count,
                      index_size, index_size);
        const unsigned char* replacements =
            view_data(context, accessor.sparse.values.bufferView, accessor.sparse.values.byteOffset, count,
                      element_size, element_size);
        for (std::size_t i = 0; i < count; ++i) {
            auto target =
                static_cast<std::size_t>(read_component(indices + i * index_size, index_type, false));
            if (target >= accessor.count)
                context.fail(fmt::format("sparse index {} is past its {} elements", target, accessor.count));
            for (int c = 0; c < components; ++c)
                values[target * components + c] = read_component(replacements + i * element_size + c * size,
                                                                 accessor.componentType, accessor.normalized);
        }
    }
    return values;
}

} // namespace

std::vector<float> read_float_accessor(const tinygltf::Model& model, int index, int components,
                                       const std::string& file, const std::string& what)
{
    AccessorContext context{model, file, what, index};
    std::vector<double> values = read_accessor(context, components);
    const tinygltf::Accessor& accessor = model.accessors[index];
    if (accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && !accessor.normalized)
        context.fail("holds integers that are not normalized; expected floats");
    std::vector<float> result(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
        result[i] = static_cast<float>(values[i]);
        if (!std::isfinite(result[i]))
            context.fail("holds a NaN or infinite value");
    }
    return result;
}

std::vector<std::uint32_t> read_index_accessor(const tinygltf::Model& model, int index,
                                               std::size_t vertex_count, const std::string& file,
                                               const std::string& what)
{
    AccessorContext context{model, file, what, index};
    std::vector<double> values = read_accessor(context, 1);
    int type = model.accessors[index].componentType;
    if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        context.fail("indices must be unsigned byte, short or int");
    std::vector<std::uint32_t> result(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (values[i] >= static_cast<double>(vertex_count))
            context.fail(fmt::format("index {} is past the {} vertices", values[i], vertex_count));
        result[i] = static_cast<std::uint32_t>(values[i]);
    }
    return result;
}

} // namespace modestack::scene
