// A contiguous array of floats held either on the heap (a std::vector) or in pages mapped from a
// file: the storage of an image's values (DepthImage, ImageChannel), so that an image that
// lightvol-image decoded into shared memory is used where it lies, without a copy or a second set
// of fresh pages (core/detail/image_helper.h).
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <initializer_list>
#include <utility>
#include <vector>

namespace lightvol {

// The subset of std::vector<float>'s interface the library and its users take from an image's
// values. Its data() is stable while it lives and is neither resized nor assigned. Mapped pages
// are private to this process (copy on write): writing to them is allowed and changes nothing
// else. Anything that changes the size first moves the values to the heap.
class FloatBuffer {
 public:
  using value_type = float;
  using size_type = std::size_t;
  using difference_type = std::ptrdiff_t;
  using reference = float&;
  using const_reference = const float&;
  using pointer = float*;
  using const_pointer = const float*;
  using iterator = float*;
  using const_iterator = const float*;

  FloatBuffer() = default;
  FloatBuffer(std::vector<float> values) : heap_(std::move(values)) {}  // NOLINT: implicit
  FloatBuffer(std::initializer_list<float> values) : heap_(values) {}
  explicit FloatBuffer(std::size_t n, float value = 0.0f) : heap_(n, value) {}
  FloatBuffer(const FloatBuffer& other) : heap_(other.begin(), other.end()) {}
  FloatBuffer(FloatBuffer&& other) noexcept { swap(other); }
  FloatBuffer& operator=(const FloatBuffer& other) {
    if (this != &other) {
      FloatBuffer copy(other);
      swap(copy);
    }
    return *this;
  }
  FloatBuffer& operator=(FloatBuffer&& other) noexcept {
    FloatBuffer taken(std::move(other));
    swap(taken);
    return *this;
  }
  ~FloatBuffer() { unmap(); }

  // Takes over `n` floats at `mapped`, the start of a mapping of `mapped_bytes` bytes (mmap's),
  // unmapped when this buffer ends or moves its values to the heap.
  static FloatBuffer adopt_mapping(float* mapped, std::size_t n, std::size_t mapped_bytes) {
    FloatBuffer buffer;
    buffer.mapped_ = mapped;
    buffer.mapped_size_ = n;
    buffer.mapped_bytes_ = mapped_bytes;
    return buffer;
  }
  bool mapped() const { return mapped_ != nullptr; }

  void swap(FloatBuffer& other) noexcept {
    heap_.swap(other.heap_);
    std::swap(mapped_, other.mapped_);
    std::swap(mapped_size_, other.mapped_size_);
    std::swap(mapped_bytes_, other.mapped_bytes_);
  }

  float* data() { return mapped_ ? mapped_ : heap_.data(); }
  const float* data() const { return mapped_ ? mapped_ : heap_.data(); }
  std::size_t size() const { return mapped_ ? mapped_size_ : heap_.size(); }
  bool empty() const { return size() == 0; }
  float& operator[](std::size_t i) { return data()[i]; }
  const float& operator[](std::size_t i) const { return data()[i]; }
  float* begin() { return data(); }
  float* end() { return data() + size(); }
  const float* begin() const { return data(); }
  const float* end() const { return data() + size(); }
  const float* cbegin() const { return begin(); }
  const float* cend() const { return end(); }
  float& front() { return data()[0]; }
  float& back() { return data()[size() - 1]; }
  const float& front() const { return data()[0]; }
  const float& back() const { return data()[size() - 1]; }

  void resize(std::size_t n) {
    to_heap();
    heap_.resize(n);
  }
  void resize(std::size_t n, float value) {
    to_heap();
    heap_.resize(n, value);
  }
  void reserve(std::size_t n) {
    to_heap();
    heap_.reserve(n);
  }
  void assign(std::size_t n, float value) {
    unmap();
    heap_.assign(n, value);
  }
  template <class It>
  void assign(It first, It last) {
    std::vector<float> values(first, last);  // `first` may point into this buffer
    unmap();
    heap_ = std::move(values);
  }
  // Inserts [first, last) (which must not point into this buffer) before `position`.
  template <class It>
  float* insert(const float* position, It first, It last) {
    const auto at = position - data();
    to_heap();
    return heap_.data() + (heap_.insert(heap_.begin() + at, first, last) - heap_.begin());
  }
  void push_back(float value) {
    to_heap();
    heap_.push_back(value);
  }
  void clear() {
    unmap();
    heap_.clear();
  }

  std::vector<float> to_vector() const { return {begin(), end()}; }
  explicit operator std::vector<float>() const { return to_vector(); }

  friend bool operator==(const FloatBuffer& a, const FloatBuffer& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end());
  }
  friend bool operator!=(const FloatBuffer& a, const FloatBuffer& b) { return !(a == b); }

 private:
  void unmap() {
    if (mapped_ != nullptr) ::munmap(mapped_, mapped_bytes_);
    mapped_ = nullptr;
    mapped_size_ = mapped_bytes_ = 0;
  }
  void to_heap() {
    if (mapped_ == nullptr) return;
    std::vector<float> values(begin(), end());
    unmap();
    heap_ = std::move(values);
  }

  std::vector<float> heap_;
  float* mapped_ = nullptr;  // when set, the values (heap_ is then empty)
  std::size_t mapped_size_ = 0;
  std::size_t mapped_bytes_ = 0;
};

}  // namespace lightvol
