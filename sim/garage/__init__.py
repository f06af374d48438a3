"""The garage: a racer's model folders, the `model` commands' library, DeepRacer import and
bundles. Nothing here imports torch: policies are handled as safetensors bytes."""
