// Placeholder translation unit; the OpenMesh adapter is being written.
namespace normalflow::detail { int openmesh_adapter_placeholder = 0; }
