// Move-only owners of device memory (cudaMalloc) and pinned host memory (cudaMallocHost).
// Allocation failures come back as Status (RESOURCE_EXHAUSTED when memory ran out); the
// destructor frees and ignores errors (nothing useful can be done with them there).
//
//   auto buffer = DeviceBuffer<float>::Allocate(n);
//   if (!buffer.ok()) return buffer.status();
#pragma once

#include <cuda_runtime_api.h>

#include <cstddef>
#include <utility>

#include "gpu/core/cuda_status.h"

namespace localizer::gpu {

template <typename T, bool kPinnedHost>
class CudaMemory {
 public:
  CudaMemory() = default;
  ~CudaMemory() { Reset(); }
  CudaMemory(CudaMemory&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
  CudaMemory& operator=(CudaMemory&& other) noexcept {
    if (this != &other) {
      Reset();
      data_ = std::exchange(other.data_, nullptr);
      size_ = std::exchange(other.size_, 0);
    }
    return *this;
  }
  CudaMemory(const CudaMemory&) = delete;
  CudaMemory& operator=(const CudaMemory&) = delete;

  // `count` elements (0 gives an empty buffer without calling CUDA).
  static StatusOr<CudaMemory> Allocate(std::size_t count) {
    CudaMemory memory;
    if (count == 0) return StatusOr<CudaMemory>(std::move(memory));
    void* raw = nullptr;
    const cudaError_t result =
        kPinnedHost ? cudaMallocHost(&raw, count * sizeof(T)) : cudaMalloc(&raw, count * sizeof(T));
    LOCALIZER_CUDA_RETURN_IF_ERROR(result, kPinnedHost ? "cudaMallocHost" : "cudaMalloc");
    memory.data_ = static_cast<T*>(raw);
    memory.size_ = count;
    return StatusOr<CudaMemory>(std::move(memory));
  }

  // Grows to at least `count` elements (contents are not kept); no-op when large enough.
  Status Reserve(std::size_t count) {
    if (count <= size_) return Status::Ok();
    auto bigger = Allocate(count);
    if (!bigger.ok()) return bigger.status();
    *this = std::move(bigger).value();
    return Status::Ok();
  }

  void Reset() {
    if (data_ != nullptr) {
      if (kPinnedHost)
        cudaFreeHost(data_);
      else
        cudaFree(data_);
    }
    data_ = nullptr;
    size_ = 0;
  }

  T* data() const { return data_; }
  std::size_t size() const { return size_; }
  std::size_t bytes() const { return size_ * sizeof(T); }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

template <typename T>
using DeviceBuffer = CudaMemory<T, false>;
template <typename T>
using PinnedBuffer = CudaMemory<T, true>;

// An owned cudaStream_t (non-blocking with respect to the legacy default stream).
class CudaStream {
 public:
  CudaStream() = default;
  ~CudaStream() {
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
  }
  CudaStream(CudaStream&& other) noexcept : stream_(std::exchange(other.stream_, nullptr)) {}
  CudaStream& operator=(CudaStream&& other) noexcept {
    std::swap(stream_, other.stream_);
    return *this;
  }
  CudaStream(const CudaStream&) = delete;
  CudaStream& operator=(const CudaStream&) = delete;

  static StatusOr<CudaStream> Create() {
    CudaStream s;
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaStreamCreateWithFlags(&s.stream_, cudaStreamNonBlocking), "cudaStreamCreate");
    return StatusOr<CudaStream>(std::move(s));
  }
  cudaStream_t get() const { return stream_; }
  Status Synchronize() const { return FromCuda(cudaStreamSynchronize(stream_), "cudaStreamSynchronize"); }

 private:
  cudaStream_t stream_ = nullptr;
};

}  // namespace localizer::gpu
