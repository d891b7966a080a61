"""The ROS adapter layer: conversions, readers, parameters, runners and execution
helpers shared by the nodes."""
