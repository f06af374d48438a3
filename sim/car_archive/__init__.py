"""DeepRacer car archives: reading the `.tar.gz` the physical car loads (model_metadata.json
and a frozen TensorFlow graph, agent/model.pb) and running that graph without TensorFlow.

The archive, protobuf and graph readers never import torch; only the graph runner and the
driver built on it do, since they run a policy. Writing an archive from a trained policy is
`sim.car_export`, above the training.
"""
