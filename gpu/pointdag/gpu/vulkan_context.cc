#include "pointdag/gpu/vulkan_context.h"

#include <vulkan/vulkan.h>

#include <cstring>
#include <map>

namespace pointdag::gpu {
namespace {

// One Run: a descriptor set per dispatch, from a pool sized for this many.
constexpr uint32_t kMaxDispatches = 64, kMaxBuffers = 16;

std::string VkError(const std::string& what, VkResult result) { return what + " failed (VkResult " + std::to_string(result) + ")"; }

// Discrete first, then integrated, virtual, and a CPU implementation last.
int DeviceRank(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
    default: return 0;
  }
}

}  // namespace

struct VulkanContext::Impl {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t queue_family = 0;
  uint32_t host_memory_type = 0;
  VkCommandPool pool = VK_NULL_HANDLE;
  VkDescriptorPool descriptors = VK_NULL_HANDLE;
  std::map<std::string, Kernel, std::less<>> kernels;

  ~Impl() {
    if (device) {
      vkDeviceWaitIdle(device);
      for (auto& [name, k] : kernels) {
        vkDestroyPipeline(device, reinterpret_cast<VkPipeline>(k.pipeline), nullptr);
        vkDestroyPipelineLayout(device, reinterpret_cast<VkPipelineLayout>(k.layout), nullptr);
        vkDestroyDescriptorSetLayout(device, reinterpret_cast<VkDescriptorSetLayout>(k.set_layout), nullptr);
      }
      if (descriptors) vkDestroyDescriptorPool(device, descriptors, nullptr);
      if (pool) vkDestroyCommandPool(device, pool, nullptr);
      vkDestroyDevice(device, nullptr);
    }
    if (instance) vkDestroyInstance(instance, nullptr);
  }
};

VulkanContext::VulkanContext(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VulkanContext::~VulkanContext() = default;

StatusOr<std::unique_ptr<VulkanContext>> VulkanContext::Create() {
  auto impl = std::make_unique<Impl>();
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "pointdag";
  app.apiVersion = VK_API_VERSION_1_1;
  VkInstanceCreateInfo instance_info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  instance_info.pApplicationInfo = &app;
  if (VkResult r = vkCreateInstance(&instance_info, nullptr, &impl->instance); r != VK_SUCCESS) {
    return Unsupported(VkError("vkCreateInstance (is a Vulkan driver installed? mesa-vulkan-drivers gives lavapipe)", r));
  }
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(impl->instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(impl->instance, &count, devices.data());
  // The best-ranked device with a compute queue and 64-bit integers in shaders.
  int best_rank = 0;
  VkPhysicalDeviceProperties chosen{};
  for (VkPhysicalDevice d : devices) {
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(d, &props);
    VkPhysicalDeviceFeatures features;
    vkGetPhysicalDeviceFeatures(d, &features);
    uint32_t families = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d, &families, nullptr);
    std::vector<VkQueueFamilyProperties> family_props(families);
    vkGetPhysicalDeviceQueueFamilyProperties(d, &families, family_props.data());
    for (uint32_t f = 0; f < families; ++f) {
      const int rank = DeviceRank(props.deviceType);
      if ((family_props[f].queueFlags & VK_QUEUE_COMPUTE_BIT) && features.shaderInt64 && rank > best_rank) {
        best_rank = rank;
        impl->physical = d;
        impl->queue_family = f;
        chosen = props;
        break;
      }
    }
  }
  if (!impl->physical) return Unsupported("no Vulkan device with compute and 64-bit shader integers");

  VkPhysicalDeviceMemoryProperties memory;
  vkGetPhysicalDeviceMemoryProperties(impl->physical, &memory);
  bool found = false;
  for (uint32_t i = 0; i < memory.memoryTypeCount && !found; ++i) {
    const auto flags = memory.memoryTypes[i].propertyFlags;
    if ((flags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) && (flags & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)) {
      impl->host_memory_type = i;
      found = true;
    }
  }
  if (!found) return Unsupported("the Vulkan device has no host-visible coherent memory");

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue_info.queueFamilyIndex = impl->queue_family;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;
  VkPhysicalDeviceFeatures enabled{};
  enabled.shaderInt64 = VK_TRUE;
  VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  device_info.queueCreateInfoCount = 1;
  device_info.pQueueCreateInfos = &queue_info;
  device_info.pEnabledFeatures = &enabled;
  if (VkResult r = vkCreateDevice(impl->physical, &device_info, nullptr, &impl->device); r != VK_SUCCESS) {
    return Unsupported(VkError("vkCreateDevice", r));
  }
  vkGetDeviceQueue(impl->device, impl->queue_family, 0, &impl->queue);
  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool_info.queueFamilyIndex = impl->queue_family;
  if (VkResult r = vkCreateCommandPool(impl->device, &pool_info, nullptr, &impl->pool); r != VK_SUCCESS) {
    return Internal(VkError("vkCreateCommandPool", r));
  }
  const VkDescriptorPoolSize sizes{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kMaxDispatches * kMaxBuffers};
  VkDescriptorPoolCreateInfo dp{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dp.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  dp.maxSets = kMaxDispatches;
  dp.poolSizeCount = 1;
  dp.pPoolSizes = &sizes;
  if (VkResult r = vkCreateDescriptorPool(impl->device, &dp, nullptr, &impl->descriptors); r != VK_SUCCESS) {
    return Internal(VkError("vkCreateDescriptorPool", r));
  }
  std::unique_ptr<VulkanContext> out(new VulkanContext(std::move(impl)));
  out->device_name_ = chosen.deviceName;
  out->device_key_ = out->device_name_ + " / driver " + std::to_string(chosen.driverVersion) + " / " +
                     std::to_string(chosen.vendorID) + ":" + std::to_string(chosen.deviceID);
  out->software_ = chosen.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  return out;
}

Buffer::Buffer(Buffer&& other) noexcept
    : context_(other.context_), size_(other.size_), mapped_(other.mapped_), buffer_(other.buffer_), memory_(other.memory_) {
  other.buffer_ = other.memory_ = 0;
  other.mapped_ = nullptr;
}

Buffer& Buffer::operator=(Buffer&& other) noexcept {
  if (this == &other) return *this;
  Release();
  context_ = other.context_;
  size_ = other.size_;
  mapped_ = other.mapped_;
  buffer_ = other.buffer_;
  memory_ = other.memory_;
  other.buffer_ = other.memory_ = 0;
  other.mapped_ = nullptr;
  return *this;
}

Buffer::~Buffer() { Release(); }

void Buffer::Release() {
  if (!buffer_) return;
  VkDevice device = context_->impl_->device;
  vkDestroyBuffer(device, reinterpret_cast<VkBuffer>(buffer_), nullptr);
  vkFreeMemory(device, reinterpret_cast<VkDeviceMemory>(memory_), nullptr);
  buffer_ = memory_ = 0;
  mapped_ = nullptr;
}

StatusOr<Buffer> VulkanContext::CreateBuffer(size_t bytes) {
  Buffer out(this, bytes);
  VkDevice device = impl_->device;
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = std::max<size_t>(bytes, 16);
  info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer buffer;
  if (VkResult r = vkCreateBuffer(device, &info, nullptr, &buffer); r != VK_SUCCESS) return ResourceLimit(VkError("vkCreateBuffer", r));
  out.buffer_ = reinterpret_cast<uint64_t>(buffer);
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, buffer, &req);
  if (!(req.memoryTypeBits & (1u << impl_->host_memory_type))) return Unsupported("buffer memory type is not host-visible");
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = impl_->host_memory_type;
  VkDeviceMemory memory;
  if (VkResult r = vkAllocateMemory(device, &alloc, nullptr, &memory); r != VK_SUCCESS) {
    return ResourceLimit(VkError("vkAllocateMemory of " + std::to_string(req.size) + " bytes", r));
  }
  out.memory_ = reinterpret_cast<uint64_t>(memory);
  vkBindBufferMemory(device, buffer, memory, 0);
  if (VkResult r = vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &out.mapped_); r != VK_SUCCESS) return Internal(VkError("vkMapMemory", r));
  return out;
}

StatusOr<const Kernel*> VulkanContext::GetKernel(std::string_view name, std::span<const uint32_t> spirv, uint32_t buffers,
                                                 uint32_t push_bytes) {
  std::lock_guard lock(mutex_);
  if (auto it = impl_->kernels.find(name); it != impl_->kernels.end()) return &it->second;
  VkDevice device = impl_->device;
  std::vector<VkDescriptorSetLayoutBinding> bindings(buffers);
  for (uint32_t i = 0; i < buffers; ++i) bindings[i] = {i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.bindingCount = buffers;
  set_info.pBindings = bindings.data();
  Kernel k;
  k.buffers = buffers;
  k.push_bytes = push_bytes;
  VkDescriptorSetLayout set_layout;
  if (VkResult r = vkCreateDescriptorSetLayout(device, &set_info, nullptr, &set_layout); r != VK_SUCCESS) {
    return Internal(VkError("vkCreateDescriptorSetLayout", r));
  }
  k.set_layout = reinterpret_cast<uint64_t>(set_layout);
  const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes};
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &set_layout;
  layout_info.pushConstantRangeCount = push_bytes ? 1 : 0;
  layout_info.pPushConstantRanges = &push;
  VkPipelineLayout layout;
  if (VkResult r = vkCreatePipelineLayout(device, &layout_info, nullptr, &layout); r != VK_SUCCESS) {
    return Internal(VkError("vkCreatePipelineLayout", r));
  }
  k.layout = reinterpret_cast<uint64_t>(layout);
  VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  module_info.codeSize = spirv.size_bytes();
  module_info.pCode = spirv.data();
  VkShaderModule module;
  if (VkResult r = vkCreateShaderModule(device, &module_info, nullptr, &module); r != VK_SUCCESS) {
    return Internal(VkError("vkCreateShaderModule", r));
  }
  VkComputePipelineCreateInfo pipeline_info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  pipeline_info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_COMPUTE_BIT, module, "main", nullptr};
  pipeline_info.layout = layout;
  VkPipeline pipeline;
  const VkResult r = vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &pipeline);
  vkDestroyShaderModule(device, module, nullptr);
  if (r != VK_SUCCESS) return Internal(VkError("vkCreateComputePipelines", r));
  k.pipeline = reinterpret_cast<uint64_t>(pipeline);
  return &impl_->kernels.emplace(std::string(name), k).first->second;
}

Status VulkanContext::Run(std::span<const Dispatch> dispatches) {
  if (dispatches.size() > kMaxDispatches) return Internal("more than " + std::to_string(kMaxDispatches) + " dispatches in one submission");
  for (const Dispatch& d : dispatches) {
    if (d.buffers.size() != d.kernel->buffers || d.buffers.size() > kMaxBuffers) {
      return Internal("kernel takes " + std::to_string(d.kernel->buffers) + " buffers");
    }
    if (d.kernel->push_bytes > sizeof(d.push)) return Internal("kernel push constants are larger than a Dispatch holds");
  }
  std::lock_guard lock(mutex_);
  VkDevice device = impl_->device;
  std::vector<VkDescriptorSet> sets(dispatches.size());
  std::vector<VkDescriptorSetLayout> set_layouts;
  for (const Dispatch& d : dispatches) set_layouts.push_back(reinterpret_cast<VkDescriptorSetLayout>(d.kernel->set_layout));
  VkDescriptorSetAllocateInfo set_alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  set_alloc.descriptorPool = impl_->descriptors;
  set_alloc.descriptorSetCount = static_cast<uint32_t>(sets.size());
  set_alloc.pSetLayouts = set_layouts.data();
  if (VkResult r = vkAllocateDescriptorSets(device, &set_alloc, sets.data()); r != VK_SUCCESS) return Internal(VkError("vkAllocateDescriptorSets", r));
  std::vector<VkDescriptorBufferInfo> infos;
  infos.reserve(dispatches.size() * kMaxBuffers);  // no reallocation: writes point into it
  std::vector<VkWriteDescriptorSet> writes;
  for (size_t k = 0; k < dispatches.size(); ++k) {
    for (size_t i = 0; i < dispatches[k].buffers.size(); ++i) {
      infos.push_back({reinterpret_cast<VkBuffer>(dispatches[k].buffers[i]->buffer_), 0, VK_WHOLE_SIZE});
      writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[k], static_cast<uint32_t>(i), 0, 1,
                        VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, nullptr, &infos.back(), nullptr});
    }
  }
  vkUpdateDescriptorSets(device, static_cast<uint32_t>(writes.size()), writes.data(), 0, nullptr);

  VkCommandBufferAllocateInfo cb_alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cb_alloc.commandPool = impl_->pool;
  cb_alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cb_alloc.commandBufferCount = 1;
  VkCommandBuffer cb;
  vkAllocateCommandBuffers(device, &cb_alloc, &cb);
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkBeginCommandBuffer(cb, &begin);
  for (size_t k = 0; k < dispatches.size(); ++k) {
    const Dispatch& d = dispatches[k];
    const auto layout = reinterpret_cast<VkPipelineLayout>(d.kernel->layout);
    if (k > 0) {  // each dispatch reads what the previous ones wrote
      VkMemoryBarrier between{VK_STRUCTURE_TYPE_MEMORY_BARRIER, nullptr, VK_ACCESS_SHADER_WRITE_BIT,
                              VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT};
      vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &between, 0, nullptr, 0, nullptr);
    }
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, reinterpret_cast<VkPipeline>(d.kernel->pipeline));
    vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 1, &sets[k], 0, nullptr);
    if (d.kernel->push_bytes) vkCmdPushConstants(cb, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, d.kernel->push_bytes, d.push.data());
    vkCmdDispatch(cb, d.groups_x, d.groups_y, 1);
  }
  // Make the shaders' writes visible to the host's reads of the mapped memory.
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER, nullptr, VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_HOST_READ_BIT};
  vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
  vkEndCommandBuffer(cb);

  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence;
  vkCreateFence(device, &fence_info, nullptr, &fence);
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cb;
  VkResult r = vkQueueSubmit(impl_->queue, 1, &submit, fence);
  if (r == VK_SUCCESS) r = vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX);
  vkDestroyFence(device, fence, nullptr);
  vkFreeCommandBuffers(device, impl_->pool, 1, &cb);
  vkFreeDescriptorSets(device, impl_->descriptors, static_cast<uint32_t>(sets.size()), sets.data());
  if (r != VK_SUCCESS) return Internal(VkError("the compute dispatch", r));
  return Status::Ok();
}

}  // namespace pointdag::gpu
