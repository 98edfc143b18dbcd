#!/usr/bin/env python3
"""Test helper: publishes /diagnostics statuses with given names, levels and hardware ids at 2 Hz,
as the platform's nodes do through diagnostic_updater.

~statuses: list of [name, level (0 OK, 1 WARN, 2 ERROR), hardware_id]
"""
import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue


def main():
    rospy.init_node('fake_diagnostics')
    statuses = [DiagnosticStatus(level=int(level), name=name, hardware_id=hw, message='test status',
                                 values=[KeyValue('source', rospy.get_name())])
                for name, level, hw in rospy.get_param('~statuses')]
    pub = rospy.Publisher('/diagnostics', DiagnosticArray, queue_size=10)
    rate = rospy.Rate(2.0)
    while not rospy.is_shutdown():
        msg = DiagnosticArray(status=statuses)
        msg.header.stamp = rospy.Time.now()
        pub.publish(msg)
        try:
            rate.sleep()
        except rospy.ROSInterruptException:
            break


if __name__ == '__main__':
    main()
