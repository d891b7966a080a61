"""The ROS adapter layer: what the node executables (:mod:`icub_pmp.nodes`), the ``icub`` CLI
and the demo share, and nothing the numerical cores may import.

- :mod:`.conversions`: message <-> numpy conversions and message validation;
- :mod:`.raw_messages`: the 1 kHz messages read and written as CDR bytes;
- :mod:`.parameters`: a node's configuration dataclasses declared as ROS parameters;
- :mod:`.node_runner`: the ``main()`` of every node; :mod:`.subscriber_wait`: waiting for a
  matched subscriber; :mod:`.qos`: QoS matching; :mod:`.msg_types`: interface names;
- :mod:`.bag_recorder`, :mod:`.bag_player`: ``icub bag record`` / ``play`` on rclpy;
- :mod:`.probe`: an in-process node for tests and the demo;
- :mod:`.joint_state_cache`: the latest /joint_states read on demand;
- :mod:`.trajectory_action_server`: the controller's FollowJointTrajectory action;
  :mod:`.goal_execution`: executing a plan through it and judging the arrival (the planners'
  actions);
- node configurations that are not algorithms (:mod:`.cartesian_node_config`,
  :mod:`.pmp_node_config`, :mod:`.posture_publisher_config`,
  :mod:`.robot_state_publisher_config`).
"""
