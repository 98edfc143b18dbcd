#!/usr/bin/env python3
"""rostest helper: the topics the operator view shows, at low rates. Augmented stereo: 320x180 JPEG
frames with the frame number (10 Hz); distances sweep through the three colours (period 4 s);
tank energies and two /diagnostics_agg groups."""
import math

import cv2
import numpy as np
import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Float64, Float64MultiArray


def jpeg(n, eye):
    img = np.zeros((180, 320, 3), np.uint8)
    img[:] = (40, 80, 40) if eye == 'left' else (80, 40, 40)
    cv2.putText(img, '%s %d' % (eye, n), (20, 100), cv2.FONT_HERSHEY_SIMPLEX, 1.2, (255, 255, 255), 2)
    return cv2.imencode('.jpg', img)[1].tobytes()


def main():
    rospy.init_node('fake_platform')
    images = {eye: rospy.Publisher('/visual_feedback/%s/image/compressed' % eye, CompressedImage, queue_size=2)
              for eye in ('left', 'right')}
    dist = rospy.Publisher('/collision/distances', Float64MultiArray, queue_size=2)
    tanks = [rospy.Publisher('/teleop/%s/energy' % t, Float64, queue_size=2) for t in ('tank_master', 'tank_slave')]
    agg = rospy.Publisher('/diagnostics_agg', DiagnosticArray, queue_size=2)
    rate = rospy.Rate(10)
    n = 0
    while not rospy.is_shutdown():
        n += 1
        stamp = rospy.Time.now()
        for eye, pub in images.items():
            if pub.get_num_connections():
                msg = CompressedImage(format='bgr8; jpeg compressed bgr8', data=jpeg(n, eye))
                msg.header.stamp = stamp
                pub.publish(msg)
        phase = 2 * math.pi * n / 40.0
        d = 0.015 + 0.015 * math.sin(phase)          # 0 .. 30 mm: red, yellow and green
        dist.publish(Float64MultiArray(data=[d, 0.03 - d, 0.05, float('nan')]))
        for i, pub in enumerate(tanks):
            pub.publish(Float64(data=10.0 + i + math.sin(phase)))
        if n % 10 == 0:
            a = DiagnosticArray()
            a.header.stamp = stamp
            a.status = [DiagnosticStatus(level=0, name='/Collision', message='OK'),
                        DiagnosticStatus(level=1, name='/Teleoperation', message='tank low'),
                        DiagnosticStatus(level=0, name='/Collision/colliding_regions: inputs', message='OK')]
            agg.publish(a)
        rate.sleep()


if __name__ == '__main__':
    main()
