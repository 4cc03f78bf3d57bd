#pragma once
// The backend section's keys as a ConfigField table (names, members, allowed ranges): read by the
// config parser and checked by validateBackendConfig. Kept out of backend_config.h so the backend's
// public API carries neither the table machinery nor JSON.

#include <span>

#include "voca/backend/backend_config.h"
#include "voca/config/config_field.h"

namespace voca {

std::span<const ConfigField<BackendConfig>> backendConfigFields();

}  // namespace voca
