"""Embedded sensors on the hand: transfer laws from the FE and a real sensor's behaviour.

The FE stage reads the force on sensor patches inside the phalanx (`softhand.fem.sensors`);
this stage fits, per design and placement, the law from the force on the skin to the patch's
reading (`softhand.sensors.transfer`, shipped in ``calibration/sensors``), and follows it with
a real sensor's electronics (`softhand.sensors.device`). The handshake env
(`softhand.envs`) applies both to each sensing region's load.
"""
