// A buffer for scratch whose every value is written before it is read. It grows
// without initialising or copying: std::vector's resize zeroes the new elements
// (and copies the old ones when it reallocates), which on band-sized buffers
// costs a single-threaded memset pass and the kernel's page clearing on top of
// the pass that fills them.
#pragma once

#include <cstddef>
#include <memory>

namespace modestack {

template <typename T> class ScratchBuffer {
public:
    /// Makes room for `size` values; the contents are unspecified afterwards.
    void resize(std::size_t size)
    {
        if (size > m_capacity) {
            m_data.reset();  // free the old block before taking the larger one
            m_data.reset(new T[size]);
            m_capacity = size;
        }
        m_size = size;
    }

    T* data() { return m_data.get(); }
    const T* data() const { return m_data.get(); }
    std::size_t size() const { return m_size; }
    T* begin() { return data(); }
    T* end() { return data() + m_size; }
    const T* begin() const { return data(); }
    const T* end() const { return data() + m_size; }
    T& operator[](std::size_t i) { return m_data[i]; }
    const T& operator[](std::size_t i) const { return m_data[i]; }

private:
    std::unique_ptr<T[]> m_data;
    std::size_t m_size = 0;
    std::size_t m_capacity = 0;
};

}  // namespace modestack
