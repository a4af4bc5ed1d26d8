// Large allocations on transparent huge pages.
//
// A 1080p shot moves gigabytes through fresh buffers (frames, bands, planes).
// With 4 KiB pages every first touch is a page fault, and on a VM each fault
// is dear: the fault path was 9 % of `denoise`'s CPU at 1080p. Debian's kernel
// gives huge pages only where a program asks (transparent_hugepage=madvise), so
// the global operator new asks for allocations of at least kHugeMinimum bytes:
// 2 MiB-aligned, rounded up to whole huge pages, advised MADV_HUGEPAGE before
// anything touches them. Smaller ones go to malloc as before; every one is
// released by free(), so the matching delete needs nothing special.
//
// Linked into the executables only (not the libraries the tests link), and not
// under a sanitizer, which brings its own allocator.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define MODESTACK_SANITIZER_ALLOCATOR 1
#endif
#endif
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__) && !defined(MODESTACK_SANITIZER_ALLOCATOR)

#include <cstdlib>
#include <new>
#include <sys/mman.h>

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
// 32 MiB: a block's last huge page may be mostly unused, and with blocks from
// 4 MiB up that rounding put a kept 1080p run 8 % over a tight --max-memory
// (12 frames at 600M: 682 MB against 629). From 32 MiB up the run stays within
// it (621 MB) and is as fast: the shot-sized buffers are the ones that fault.
constexpr std::size_t kHugeMinimum = 16 * kHugePage;

void* allocate(std::size_t size) noexcept
{
    if (size < kHugeMinimum)
        return std::malloc(size == 0 ? 1 : size);
    const std::size_t rounded = (size + kHugePage - 1) / kHugePage * kHugePage;
    void* memory = std::aligned_alloc(kHugePage, rounded);
    if (memory != nullptr)
        madvise(memory, rounded, MADV_HUGEPAGE); // advice only: a refusal leaves small pages
    return memory;
}

} // namespace

void* operator new(std::size_t size)
{
    for (;;) {
        if (void* memory = allocate(size))
            return memory;
        std::new_handler handler = std::get_new_handler();
        if (handler == nullptr)
            throw std::bad_alloc();
        handler();
    }
}

void* operator new[](std::size_t size) { return operator new(size); }

void* operator new(std::size_t size, const std::nothrow_t&) noexcept
{
    try {
        return operator new(size);
    } catch (...) {
        return nullptr;
    }
}

void* operator new[](std::size_t size, const std::nothrow_t&) noexcept
{
    return operator new(size, std::nothrow);
}

void operator delete(void* memory) noexcept { std::free(memory); }
void operator delete[](void* memory) noexcept { std::free(memory); }
void operator delete(void* memory, std::size_t) noexcept { std::free(memory); }
void operator delete[](void* memory, std::size_t) noexcept { std::free(memory); }
void operator delete(void* memory, const std::nothrow_t&) noexcept { std::free(memory); }
void operator delete[](void* memory, const std::nothrow_t&) noexcept { std::free(memory); }

#endif
