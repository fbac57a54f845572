#include "vk.h"

#include <vulkan/vulkan.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <mutex>
#include <utility>

namespace shimmer::vk {

namespace {

std::string ResultName(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "success";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "out of host memory";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "out of device memory";
    case VK_ERROR_INITIALIZATION_FAILED: return "initialization failed";
    case VK_ERROR_DEVICE_LOST: return "device lost";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "no compatible Vulkan driver";
    case VK_ERROR_LAYER_NOT_PRESENT: return "layer not present";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "extension not present";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "feature not present";
    case VK_TIMEOUT: return "timeout";
    default: return "VkResult " + std::to_string(static_cast<int>(r));
  }
}

ErrorCode CodeOf(VkResult r) {
  switch (r) {
    case VK_ERROR_OUT_OF_HOST_MEMORY:
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return ErrorCode::kOutOfMemory;
    case VK_ERROR_DEVICE_LOST: return ErrorCode::kDeviceLost;
    default: return ErrorCode::kInternal;
  }
}

Error VulkanError(const std::string& what, VkResult r) { return Error{CodeOf(r), what + ": " + ResultName(r)}; }

std::string TypeName(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

int TypeRank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

int ComputeQueueFamily(VkPhysicalDevice pd) {
  std::uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, families.data());
  for (std::uint32_t i = 0; i < n; ++i)
    if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return static_cast<int>(i);
  return -1;
}

std::string HexOf(const std::uint8_t* bytes, std::size_t n) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < n; ++i) {
    out += kDigits[bytes[i] >> 4];
    out += kDigits[bytes[i] & 15];
  }
  return out;
}

DeviceInfo Describe(VkPhysicalDevice pd) {
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  subgroup.pNext = &driver;
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(pd, &props);
  DeviceInfo info;
  info.name = props.properties.deviceName;
  info.driver = driver.driverName;
  if (driver.driverInfo[0]) info.driver += std::string(" ") + driver.driverInfo;
  info.type = TypeName(props.properties.deviceType);
  info.api_version = props.properties.apiVersion;
  info.subgroup_size = subgroup.subgroupSize;
  info.quad_ops_in_compute = (subgroup.supportedOperations & VK_SUBGROUP_FEATURE_QUAD_BIT) &&
                             (subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT);
  info.max_storage_buffer_range = props.properties.limits.maxStorageBufferRange;
  info.max_uniform_buffer_range = props.properties.limits.maxUniformBufferRange;
  info.vendor_id = props.properties.vendorID;
  info.device_id = props.properties.deviceID;
  info.driver_version = props.properties.driverVersion;
  info.pipeline_cache_uuid = HexOf(props.properties.pipelineCacheUUID, VK_UUID_SIZE);
  int family = ComputeQueueFamily(pd);
  if (family >= 0) {
    std::uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
    std::vector<VkQueueFamilyProperties> families(n);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, families.data());
    if (families[family].timestampValidBits > 0) info.timestamp_period_ns = props.properties.limits.timestampPeriod;
  }
  return info;
}

// Where the validation layer's messages go; outlives the instance.
struct ValidationLog {
  std::mutex mutex;
  std::vector<std::string> messages;
};

VKAPI_ATTR VkBool32 VKAPI_CALL KeepValidationMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* log = static_cast<ValidationLog*>(user);
  const char* level = severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "error" : "warning";
  std::lock_guard lock(log->mutex);
  log->messages.push_back(std::string(level) + ": " + (data && data->pMessage ? data->pMessage : "(no text)"));
  return VK_FALSE;  // the call itself goes on
}

VkDebugUtilsMessengerCreateInfoEXT MessengerInfo(ValidationLog* log) {
  VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  info.messageSeverity =
      VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  info.pfnUserCallback = KeepValidationMessage;
  info.pUserData = log;
  return info;
}

struct Instance {
  VkInstance handle = VK_NULL_HANDLE;
  bool validation = false;  // the layer and its messenger extension are enabled
  std::string error;
};

bool HasValidationLayer() {
  std::uint32_t n = 0;
  if (vkEnumerateInstanceLayerProperties(&n, nullptr) != VK_SUCCESS) return false;
  std::vector<VkLayerProperties> available(n);
  if (vkEnumerateInstanceLayerProperties(&n, available.data()) < VK_SUCCESS) return false;
  available.resize(n);
  for (const auto& l : available)
    if (std::strcmp(l.layerName, "VK_LAYER_KHRONOS_validation") == 0) return true;
  return false;
}

// `log` non-null: validation when the layer is installed (silently without).
Instance CreateInstance(ValidationLog* log) {
  Instance out;
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "shimmer";
  app.apiVersion = VK_API_VERSION_1_2;
  std::vector<const char*> layers, extensions;
  out.validation = log && HasValidationLayer();
  VkDebugUtilsMessengerCreateInfoEXT messenger = MessengerInfo(log);
  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  if (out.validation) {
    layers.push_back("VK_LAYER_KHRONOS_validation");
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);  // provided by the layer
    ci.pNext = &messenger;                                    // also reports on vkCreateInstance/vkDestroyInstance
  }
  ci.pApplicationInfo = &app;
  ci.enabledLayerCount = static_cast<std::uint32_t>(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  ci.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
  ci.ppEnabledExtensionNames = extensions.data();
  VkResult r = vkCreateInstance(&ci, nullptr, &out.handle);
  if (r != VK_SUCCESS) {
    out.handle = VK_NULL_HANDLE;
    out.error = "no Vulkan driver could be loaded (" + ResultName(r) + "); install a driver such as Mesa lavapipe";
  }
  return out;
}

std::vector<VkPhysicalDevice> UsableDevices(VkInstance instance) {
  std::uint32_t n = 0;
  if (vkEnumeratePhysicalDevices(instance, &n, nullptr) != VK_SUCCESS) return {};
  std::vector<VkPhysicalDevice> all(n);
  if (vkEnumeratePhysicalDevices(instance, &n, all.data()) < VK_SUCCESS) return {};
  all.resize(n);
  std::vector<VkPhysicalDevice> usable;
  for (VkPhysicalDevice pd : all) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    if (p.apiVersion >= VK_API_VERSION_1_2 && ComputeQueueFamily(pd) >= 0) usable.push_back(pd);
  }
  return usable;
}

}  // namespace

struct Buffer::Impl {
  VkDevice device = VK_NULL_HANDLE;
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
};

Buffer::~Buffer() {
  if (!impl_) return;
  if (impl_->memory) vkFreeMemory(impl_->device, impl_->memory, nullptr);
  if (impl_->buffer) vkDestroyBuffer(impl_->device, impl_->buffer, nullptr);
}

struct ComputePipeline::Impl {
  VkDevice device = VK_NULL_HANDLE;
  VkShaderModule module = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSet set = VK_NULL_HANDLE;
  std::vector<BufferKind> bindings;
  std::uint32_t push_bytes = 0;
};

VkDescriptorType DescriptorType(BufferKind kind) {
  return kind == BufferKind::kUniform ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}

ComputePipeline::~ComputePipeline() {
  if (!impl_) return;
  VkDevice d = impl_->device;
  if (impl_->pool) vkDestroyDescriptorPool(d, impl_->pool, nullptr);
  if (impl_->pipeline) vkDestroyPipeline(d, impl_->pipeline, nullptr);
  if (impl_->layout) vkDestroyPipelineLayout(d, impl_->layout, nullptr);
  if (impl_->set_layout) vkDestroyDescriptorSetLayout(d, impl_->set_layout, nullptr);
  if (impl_->module) vkDestroyShaderModule(d, impl_->module, nullptr);
}

struct PipelineCache::Impl {
  VkDevice device = VK_NULL_HANDLE;
  VkPipelineCache cache = VK_NULL_HANDLE;
};

PipelineCache::~PipelineCache() {
  if (impl_ && impl_->cache) vkDestroyPipelineCache(impl_->device, impl_->cache, nullptr);
}

namespace {

// Why `data` is no cache of `info`'s device, or empty when its header fits.
std::string ForeignCacheReason(std::string_view data, const DeviceInfo& info) {
  VkPipelineCacheHeaderVersionOne header{};
  if (data.size() < sizeof header)
    return "truncated: " + std::to_string(data.size()) + " bytes, shorter than a cache header";
  std::memcpy(&header, data.data(), sizeof header);
  if (header.headerVersion != VK_PIPELINE_CACHE_HEADER_VERSION_ONE || header.headerSize < sizeof header ||
      header.headerSize > data.size())
    return "not a Vulkan pipeline cache";
  if (header.vendorID != info.vendor_id || header.deviceID != info.device_id) return "written for another device";
  if (HexOf(header.pipelineCacheUUID, VK_UUID_SIZE) != info.pipeline_cache_uuid)
    return "written by another driver build";
  return {};
}

}  // namespace

struct Context::Impl {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  std::uint32_t family = 0;
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  VkQueryPool queries = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  ValidationLog validation_log;
  std::mutex dispatch_mutex;  // the one command buffer, fence and query pool, and descriptor updates
  bool validation = false;
  bool lost = false;
  int dispatches = 0;
  int lose_device_after = -1;

  ~Impl() {
    if (device) {
      vkDeviceWaitIdle(device);
      if (queries) vkDestroyQueryPool(device, queries, nullptr);
      if (fence) vkDestroyFence(device, fence, nullptr);
      if (pool) vkDestroyCommandPool(device, pool, nullptr);
      vkDestroyDevice(device, nullptr);
    }
    if (messenger) {
      auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
      if (destroy) destroy(instance, messenger, nullptr);
    }
    if (instance) vkDestroyInstance(instance, nullptr);
  }
};

Result<std::vector<DeviceInfo>> Context::ListDevices() {
  Instance inst = CreateInstance(nullptr);
  std::vector<DeviceInfo> out;
  if (!inst.handle) return Result<std::vector<DeviceInfo>>::Failure(inst.error, ErrorCode::kInternal);
  for (VkPhysicalDevice pd : UsableDevices(inst.handle)) out.push_back(Describe(pd));
  vkDestroyInstance(inst.handle, nullptr);
  return out;
}

Result<std::unique_ptr<Context>> Context::Create(const ContextOptions& options) {
  using R = Result<std::unique_ptr<Context>>;
  std::unique_ptr<Context> ctx(new Context());
  ctx->impl_ = std::make_unique<Impl>();
  Impl& c = *ctx->impl_;
  Instance inst = CreateInstance(options.validation ? &c.validation_log : nullptr);
  if (!inst.handle) return R::Failure(inst.error, ErrorCode::kInternal);
  c.instance = inst.handle;
  c.validation = inst.validation;
  c.lose_device_after = options.lose_device_after_dispatches;
  if (c.validation) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(c.instance, "vkCreateDebugUtilsMessengerEXT"));
    VkDebugUtilsMessengerCreateInfoEXT info = MessengerInfo(&c.validation_log);
    if (!create || create(c.instance, &info, nullptr, &c.messenger) != VK_SUCCESS) c.validation = false;
  }
  std::vector<VkPhysicalDevice> devices = UsableDevices(c.instance);
  if (devices.empty())
    return R::Failure(
        "no Vulkan 1.2 device with a compute queue was found (install Mesa lavapipe: mesa-vulkan-drivers)",
        ErrorCode::kInternal);
  std::vector<VkPhysicalDevice> candidates;
  std::string names;
  for (VkPhysicalDevice pd : devices) {
    DeviceInfo info = Describe(pd);
    names += (names.empty() ? "" : ", ") + ("'" + info.name + "'");
    if (options.device_name.empty() || info.name.find(options.device_name) != std::string::npos)
      candidates.push_back(pd);
  }
  if (candidates.empty())
    return R::Failure("no Vulkan device matches '" + options.device_name + "' (available: " + names + ")");
  std::stable_sort(candidates.begin(), candidates.end(), [](VkPhysicalDevice a, VkPhysicalDevice b) {
    VkPhysicalDeviceProperties pa, pb;
    vkGetPhysicalDeviceProperties(a, &pa);
    vkGetPhysicalDeviceProperties(b, &pb);
    return TypeRank(pa.deviceType) < TypeRank(pb.deviceType);
  });
  c.physical = candidates.front();
  ctx->info_ = Describe(c.physical);
  c.family = static_cast<std::uint32_t>(ComputeQueueFamily(c.physical));

  float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = c.family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  f12.hostQueryReset = VK_FALSE;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &f12;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  VkResult r = vkCreateDevice(c.physical, &dci, nullptr, &c.device);
  if (r != VK_SUCCESS) {
    c.device = VK_NULL_HANDLE;
    return VulkanError("could not create a Vulkan device on '" + ctx->info_.name + "'", r);
  }
  vkGetDeviceQueue(c.device, c.family, 0, &c.queue);
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = c.family;
  if (r = vkCreateCommandPool(c.device, &pci, nullptr, &c.pool); r != VK_SUCCESS) {
    c.pool = VK_NULL_HANDLE;
    return VulkanError("could not create a command pool", r);
  }
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = c.pool;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  if (r = vkAllocateCommandBuffers(c.device, &cai, &c.cmd); r != VK_SUCCESS)
    return VulkanError("could not allocate a command buffer", r);
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  if (r = vkCreateFence(c.device, &fci, nullptr, &c.fence); r != VK_SUCCESS) {
    c.fence = VK_NULL_HANDLE;
    return VulkanError("could not create a fence", r);
  }
  if (ctx->info_.timestamp_period_ns > 0) {
    VkQueryPoolCreateInfo qpi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qpi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qpi.queryCount = 2;
    if (vkCreateQueryPool(c.device, &qpi, nullptr, &c.queries) != VK_SUCCESS) c.queries = VK_NULL_HANDLE;
  }
  return ctx;
}

Context::~Context() = default;

bool Context::validation_active() const { return impl_->validation; }

std::vector<std::string> Context::TakeValidationMessages() {
  std::lock_guard lock(impl_->validation_log.mutex);
  return std::exchange(impl_->validation_log.messages, {});
}

Result<std::unique_ptr<Buffer>> Context::CreateBuffer(std::size_t bytes, BufferKind kind) {
  using R = Result<std::unique_ptr<Buffer>>;
  Impl& c = *impl_;
  bytes = std::max<std::size_t>(bytes, 16);
  if (kind == BufferKind::kStorage && bytes > info_.max_storage_buffer_range)
    return R::Failure("a storage buffer of " + std::to_string(bytes >> 20) + " MiB exceeds the device's limit of " +
                          std::to_string(info_.max_storage_buffer_range >> 20) + " MiB",
                      ErrorCode::kOutOfMemory);
  if (kind == BufferKind::kUniform && bytes > info_.max_uniform_buffer_range)
    return R::Failure("a uniform buffer of " + std::to_string(bytes) + " bytes exceeds the device's limit of " +
                          std::to_string(info_.max_uniform_buffer_range) + " bytes",
                      ErrorCode::kOutOfMemory);
  std::unique_ptr<Buffer> buf(new Buffer());
  buf->impl_ = std::make_unique<Buffer::Impl>();
  buf->impl_->device = c.device;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = bytes;
  bci.usage = kind == BufferKind::kUniform ? VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT : VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkResult r = vkCreateBuffer(c.device, &bci, nullptr, &buf->impl_->buffer);
  if (r != VK_SUCCESS) {
    buf->impl_->buffer = VK_NULL_HANDLE;
    return VulkanError("could not create a buffer", r);
  }
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(c.device, buf->impl_->buffer, &req);
  VkPhysicalDeviceMemoryProperties mp;
  vkGetPhysicalDeviceMemoryProperties(c.physical, &mp);
  const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  std::uint32_t type = UINT32_MAX;
  for (std::uint32_t i = 0; i < mp.memoryTypeCount && type == UINT32_MAX; ++i)
    if ((req.memoryTypeBits & (1u << i)) && (mp.memoryTypes[i].propertyFlags & want) == want) type = i;
  if (type == UINT32_MAX) return R::Failure("the device has no host-visible coherent memory", ErrorCode::kInternal);
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = type;
  r = vkAllocateMemory(c.device, &mai, nullptr, &buf->impl_->memory);
  if (r != VK_SUCCESS) {
    buf->impl_->memory = VK_NULL_HANDLE;
    return VulkanError("could not allocate " + std::to_string(bytes >> 20) + " MiB", r);
  }
  if (r = vkBindBufferMemory(c.device, buf->impl_->buffer, buf->impl_->memory, 0); r != VK_SUCCESS)
    return VulkanError("could not bind a buffer's memory", r);
  if (r = vkMapMemory(c.device, buf->impl_->memory, 0, VK_WHOLE_SIZE, 0, &buf->mapped_); r != VK_SUCCESS)
    return VulkanError("could not map a buffer", r);
  buf->size_ = bytes;
  buf->kind_ = kind;
  std::memset(buf->mapped_, 0, bytes);
  return buf;
}

Result<std::unique_ptr<PipelineCache>> Context::CreatePipelineCache(std::string_view data) {
  using R = Result<std::unique_ptr<PipelineCache>>;
  if (!data.empty())
    if (std::string why = ForeignCacheReason(data, info_); !why.empty()) return R::Failure(why);
  std::unique_ptr<PipelineCache> cache(new PipelineCache());
  cache->impl_ = std::make_unique<PipelineCache::Impl>();
  cache->impl_->device = impl_->device;
  VkPipelineCacheCreateInfo ci{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
  ci.initialDataSize = data.size();
  ci.pInitialData = data.empty() ? nullptr : data.data();
  if (VkResult r = vkCreatePipelineCache(impl_->device, &ci, nullptr, &cache->impl_->cache); r != VK_SUCCESS) {
    cache->impl_->cache = VK_NULL_HANDLE;
    return VulkanError("could not create a pipeline cache", r);
  }
  return cache;
}

Result<std::string> Context::PipelineCacheData(const PipelineCache& cache) {
  // The size can grow between the two calls when another thread adds a
  // pipeline; VK_INCOMPLETE then asks again.
  for (;;) {
    std::size_t size = 0;
    if (VkResult r = vkGetPipelineCacheData(impl_->device, cache.impl_->cache, &size, nullptr); r != VK_SUCCESS)
      return VulkanError("could not read the pipeline cache", r);
    std::string data(size, '\0');
    VkResult r = vkGetPipelineCacheData(impl_->device, cache.impl_->cache, &size, data.data());
    if (r == VK_INCOMPLETE) continue;
    if (r != VK_SUCCESS) return VulkanError("could not read the pipeline cache", r);
    data.resize(size);
    return data;
  }
}

Result<std::unique_ptr<ComputePipeline>> Context::CreatePipeline(std::span<const std::uint32_t> spirv,
                                                                 std::span<const std::int32_t> specialization,
                                                                 std::span<const BufferKind> buffer_kinds,
                                                                 std::uint32_t push_bytes, PipelineCache* cache) {
  VkDevice d = impl_->device;
  std::unique_ptr<ComputePipeline> p(new ComputePipeline());
  p->impl_ = std::make_unique<ComputePipeline::Impl>();
  ComputePipeline::Impl& pi = *p->impl_;
  pi.device = d;
  pi.bindings.assign(buffer_kinds.begin(), buffer_kinds.end());
  const auto buffer_count = static_cast<std::uint32_t>(buffer_kinds.size());
  pi.push_bytes = push_bytes;
  auto fail = [](const std::string& what, VkResult r) -> Result<std::unique_ptr<ComputePipeline>> {
    return VulkanError("could not create the compute pipeline (" + what + ")", r);
  };
  VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  smci.codeSize = spirv.size_bytes();
  smci.pCode = spirv.data();
  if (VkResult r = vkCreateShaderModule(d, &smci, nullptr, &pi.module); r != VK_SUCCESS)
    return fail("shader module", r);
  std::vector<VkDescriptorSetLayoutBinding> bindings(buffer_count);
  for (std::uint32_t i = 0; i < buffer_count; ++i)
    bindings[i] = {i, DescriptorType(buffer_kinds[i]), 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo dsl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  dsl.bindingCount = buffer_count;
  dsl.pBindings = bindings.data();
  if (VkResult r = vkCreateDescriptorSetLayout(d, &dsl, nullptr, &pi.set_layout); r != VK_SUCCESS)
    return fail("descriptor set layout", r);
  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes};
  VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &pi.set_layout;
  plci.pushConstantRangeCount = push_bytes > 0 ? 1 : 0;
  plci.pPushConstantRanges = &range;
  if (VkResult r = vkCreatePipelineLayout(d, &plci, nullptr, &pi.layout); r != VK_SUCCESS)
    return fail("pipeline layout", r);
  std::vector<VkSpecializationMapEntry> entries(specialization.size());
  for (std::size_t i = 0; i < specialization.size(); ++i)
    entries[i] = {static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i * sizeof(std::int32_t)),
                  sizeof(std::int32_t)};
  VkSpecializationInfo si{static_cast<std::uint32_t>(entries.size()), entries.data(), specialization.size_bytes(),
                          specialization.data()};
  VkComputePipelineCreateInfo cpci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cpci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpci.stage.module = pi.module;
  cpci.stage.pName = "main";
  cpci.stage.pSpecializationInfo = specialization.empty() ? nullptr : &si;
  cpci.layout = pi.layout;
  if (VkResult r =
          vkCreateComputePipelines(d, cache ? cache->impl_->cache : VK_NULL_HANDLE, 1, &cpci, nullptr, &pi.pipeline);
      r != VK_SUCCESS)
    return fail("pipeline", r);
  const VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, buffer_count},
                                        {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, buffer_count}};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = 1;
  dpci.poolSizeCount = 2;
  dpci.pPoolSizes = sizes;
  if (VkResult r = vkCreateDescriptorPool(d, &dpci, nullptr, &pi.pool); r != VK_SUCCESS)
    return fail("descriptor pool", r);
  VkDescriptorSetAllocateInfo dsai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  dsai.descriptorPool = pi.pool;
  dsai.descriptorSetCount = 1;
  dsai.pSetLayouts = &pi.set_layout;
  if (VkResult r = vkAllocateDescriptorSets(d, &dsai, &pi.set); r != VK_SUCCESS) return fail("descriptor set", r);
  return p;
}

Result<double> Context::Dispatch(ComputePipeline& pipeline, std::span<Buffer* const> buffers,
                                 std::span<const std::byte> push, std::uint32_t groups_x, std::uint32_t groups_y) {
  Impl& c = *impl_;
  ComputePipeline::Impl& pi = *pipeline.impl_;
  std::lock_guard lock(c.dispatch_mutex);
  if (c.lost) return Result<double>::Failure("device lost", ErrorCode::kDeviceLost);
  bool match = buffers.size() == pi.bindings.size() && push.size() == pi.push_bytes;
  for (std::size_t i = 0; match && i < buffers.size(); ++i) match = buffers[i]->kind() == pi.bindings[i];
  if (!match)
    return Result<double>::Failure("dispatch does not match the pipeline's buffers or push constants",
                                   ErrorCode::kInternal);
  std::vector<VkDescriptorBufferInfo> infos(buffers.size());
  std::vector<VkWriteDescriptorSet> writes(buffers.size());
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    infos[i] = {buffers[i]->impl_->buffer, 0, VK_WHOLE_SIZE};
    writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[i].dstSet = pi.set;
    writes[i].dstBinding = static_cast<std::uint32_t>(i);
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = DescriptorType(pi.bindings[i]);
    writes[i].pBufferInfo = &infos[i];
  }
  vkUpdateDescriptorSets(c.device, static_cast<std::uint32_t>(writes.size()), writes.data(), 0, nullptr);

  if (VkResult r = vkResetCommandBuffer(c.cmd, 0); r != VK_SUCCESS)
    return VulkanError("could not reset the command buffer", r);
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  if (VkResult r = vkBeginCommandBuffer(c.cmd, &begin); r != VK_SUCCESS)
    return VulkanError("could not record the dispatch", r);
  if (c.queries) {
    vkCmdResetQueryPool(c.cmd, c.queries, 0, 2);
    vkCmdWriteTimestamp(c.cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, c.queries, 0);
  }
  vkCmdBindPipeline(c.cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pi.pipeline);
  vkCmdBindDescriptorSets(c.cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pi.layout, 0, 1, &pi.set, 0, nullptr);
  if (!push.empty())
    vkCmdPushConstants(c.cmd, pi.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, static_cast<std::uint32_t>(push.size()),
                       push.data());
  vkCmdDispatch(c.cmd, groups_x, groups_y, 1);
  if (c.queries) vkCmdWriteTimestamp(c.cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, c.queries, 1);
  // Make the shader's writes visible to the host's reads of the mapped memory.
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(c.cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0,
                       nullptr, 0, nullptr);
  if (VkResult r = vkEndCommandBuffer(c.cmd); r != VK_SUCCESS) return VulkanError("could not record the dispatch", r);

  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &c.cmd;
  auto start = std::chrono::steady_clock::now();
  VkResult r = vkQueueSubmit(c.queue, 1, &submit, c.fence);
  if (r == VK_SUCCESS) r = vkWaitForFences(c.device, 1, &c.fence, VK_TRUE, UINT64_MAX);
  if (c.lose_device_after >= 0 && c.dispatches++ >= c.lose_device_after) r = VK_ERROR_DEVICE_LOST;
  auto stop = std::chrono::steady_clock::now();
  if (r == VK_SUCCESS) r = vkResetFences(c.device, 1, &c.fence);
  if (r != VK_SUCCESS) {
    c.lost = c.lost || r == VK_ERROR_DEVICE_LOST;
    return VulkanError("the GPU dispatch failed", r);
  }
  double gpu_ms = std::chrono::duration<double, std::milli>(stop - start).count();
  if (c.queries) {
    std::uint64_t stamps[2] = {0, 0};
    if (vkGetQueryPoolResults(c.device, c.queries, 0, 2, sizeof(stamps), stamps, sizeof(std::uint64_t),
                              VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS)
      gpu_ms = double(stamps[1] - stamps[0]) * info_.timestamp_period_ns * 1e-6;
  }
  return gpu_ms;
}

}  // namespace shimmer::vk
