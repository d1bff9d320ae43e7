"""The ROS 2 plugin's command-line tools: ``sigcore ros ...`` (topics, echo, hz, call, record) and ``sigcore bag
play``, registered with sigcore by :func:`sigcore_ros2.cli.commands.register`; :mod:`.messages` is where a ROS 2
type name becomes its Python class, for the transport too. Importing this package imports nothing else: rclpy, typer
and the commands load only when a command is registered or runs."""
