"""
Thin rclpy nodes (simulator, comparator, recorder): ROS parameters in, messages out.

Nodes only wire publishers, subscriptions, services and timers, translate ROS messages and
parameters to and from ``tumble_ros.core`` objects, and hold no physics: every equation lives in
``core``, where it is tested without ROS. Each executable is a ``main()`` behind a console-script
entry point in setup.py.
"""
