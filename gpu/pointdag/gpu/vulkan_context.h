// Vulkan compute: the device, host-visible storage buffers, compute kernels from embedded SPIR-V,
// and submissions of dispatches. Which stage uses it is stage_device.h's business.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pointdag/status.h"

namespace pointdag::gpu {

class VulkanContext;

// A storage buffer the host can map (host-visible, coherent memory).
class Buffer {
 public:
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  ~Buffer();
  void* data() const { return mapped_; }
  size_t size() const { return size_; }

 private:
  friend class VulkanContext;
  Buffer(VulkanContext* context, size_t size) : context_(context), size_(size) {}
  void Release();
  VulkanContext* context_;
  size_t size_;
  void* mapped_ = nullptr;
  uint64_t buffer_ = 0, memory_ = 0;  // VkBuffer, VkDeviceMemory
};

// One compute pipeline: `buffers` storage buffers at bindings 0..n-1, push constants of `push_bytes`.
struct Kernel {
  uint64_t pipeline = 0, layout = 0, set_layout = 0;  // VkPipeline, VkPipelineLayout, VkDescriptorSetLayout
  uint32_t buffers = 0, push_bytes = 0;
};

// One dispatch of a kernel: its buffers (bindings 0..n-1), push constants, workgroups in x and y.
struct Dispatch {
  static constexpr size_t kMaxPushWords = 8;
  const Kernel* kernel = nullptr;
  std::span<const Buffer* const> buffers;
  std::array<uint32_t, kMaxPushWords> push{};
  uint32_t groups_x = 1, groups_y = 1;
};

class VulkanContext {
 public:
  // The best device there is, or why there is none.
  static StatusOr<std::unique_ptr<VulkanContext>> Create();
  ~VulkanContext();
  VulkanContext(const VulkanContext&) = delete;
  VulkanContext& operator=(const VulkanContext&) = delete;

  const std::string& device_name() const { return device_name_; }
  bool software() const { return software_; }  // a CPU implementation (lavapipe)
  // Name, driver version and vendor:device ids: what a cached calibration must match.
  const std::string& device_key() const { return device_key_; }

  StatusOr<Buffer> CreateBuffer(size_t bytes);
  StatusOr<const Kernel*> GetKernel(std::string_view name, std::span<const uint32_t> spirv, uint32_t buffers, uint32_t push_bytes);
  // Records the dispatches in order, each seeing the writes of those before it, submits them as one
  // command buffer and waits for them.
  Status Run(std::span<const Dispatch> dispatches);

 private:
  friend class Buffer;
  struct Impl;
  explicit VulkanContext(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  std::string device_name_, device_key_;
  bool software_ = false;
  std::mutex mutex_;  // one queue: submissions from tbb workers take turns
};

}  // namespace pointdag::gpu
