/* A stand-in for the OpenVDB module with the wrong ABI version: the module
 * loader must refuse it with a clear message (test_vdb_module.c). */
#include "media/vdb_module.h"

const haze_openvdb_api haze_openvdb_entry = {HAZE_OPENVDB_ABI + 1, sizeof(haze_openvdb_api), NULL,
                                             NULL};
