"""Files and text of a stereo calibration (ROS-free): the camera_info YAMLs, the accuracy
sidecar ``stereo_report.yaml`` next to them, and the frames-format extrinsics."""
import os

import numpy as np
import yaml
from saras_common.transforms import inverse, make_transform

from saras_calibration.world_frames import frame_entry, save_world_frames

__all__ = ['REPORT_FILE', 'EXTRINSICS_FILE', 'report', 'summary', 'write_outputs']

REPORT_FILE = 'stereo_report.yaml'
EXTRINSICS_FILE = 'stereo_extrinsics.yaml'


def _r(x, digits):
    return float(round(float(x), digits))


def report(res):
    """The sidecar's content (plain types): errors [px], baseline and its std [m], parameter std."""
    ho = res.holdout or {}
    rep = {'views': res.n_views, 'image_size': list(res.size), 'corner_method': res.corner_method,
           'reprojection_rms_px': {'left': _r(res.reprojection_rms_px[0], 4),
                                   'right': _r(res.reprojection_rms_px[1], 4)},
           'stereo_rms_px': _r(res.stereo_rms_px, 4),
           'epipolar_rms_px': _r(res.epipolar_rms_px, 4), 'baseline_m': _r(res.baseline_m, 7),
           'R_right_left': np.round(res.R, 8).tolist(), 'T_right_left_m': np.round(res.T, 7).tolist()}
    if ho:
        rep['holdout'] = {'folds': ho['folds'], 'left_rms_px': _r(ho['left_rms_px'], 4),
                          'right_rms_px': _r(ho['right_rms_px'], 4),
                          'transfer_rms_px': _r(ho['transfer_rms_px'], 4)}
    std = {}
    for side in ('left', 'right'):
        s = getattr(res, side).get('std')
        if s:
            std[side] = {k: _r(v, 6 if k[0] in 'fc' else 8) for k, v in s.items()}
    if ho:
        std['baseline_m'] = _r(ho['baseline_std'], 9)
        std['T_right_left_m'] = [_r(v, 9) for v in ho['T_std']]
    rep['std'] = std
    return rep


def summary(res):
    """Multi-line text for the CLI and the node's log."""
    rep = report(res)
    lines = ['%d views (%s corners), image %dx%d' % (res.n_views, res.corner_method, res.size[0], res.size[1]),
             'reprojection RMS  left %.3f px, right %.3f px; stereo %.3f px; epipolar RMS %.3f px'
             % (res.reprojection_rms_px + (res.stereo_rms_px, res.epipolar_rms_px))]
    ho = rep.get('holdout')
    if ho:
        lines.append('hold-out (%d folds) left %.3f px, right %.3f px, left->right transfer %.3f px'
                     % (ho['folds'], ho['left_rms_px'], ho['right_rms_px'], ho['transfer_rms_px']))
    base = 'baseline %.4f mm' % (res.baseline_m * 1e3)
    if 'baseline_m' in rep['std']:
        base += ' +- %.4f mm (jackknife std)' % (rep['std']['baseline_m'] * 1e3)
    lines.append(base)
    for side in ('left', 'right'):
        cam, s = getattr(res, side), rep['std'].get(side)
        if s:
            K = cam['K']
            lines.append('%-5s fx %.2f +- %.2f, fy %.2f +- %.2f, cx %.2f +- %.2f, cy %.2f +- %.2f px; '
                         'k1 %.4f +- %.4f, k2 %.4f +- %.4f' % (side, K[0, 0], s['fx'], K[1, 1], s['fy'], K[0, 2],
                                                                s['cx'], K[1, 2], s['cy'], cam['D'][0], s['k1'],
                                                                cam['D'][1], s['k2']))
    return '\n'.join(lines)


def write_outputs(res, output_dir, left_file='endoscope_left.yaml', right_file='endoscope_right.yaml',
                  left_frame='endoscope/left_optical_frame', right_frame='endoscope/right_optical_frame'):
    """Write both camera_info YAMLs, the sidecar and the extrinsics; return the frames entry
    ``left_frame -> right_frame``."""
    os.makedirs(output_dir, exist_ok=True)
    for name, text in ((left_file, res.left_yaml), (right_file, res.right_yaml)):
        with open(os.path.join(output_dir, name), 'w') as f:
            f.write(text)
    with open(os.path.join(output_dir, REPORT_FILE), 'w') as f:
        f.write('# Accuracy of %s / %s (saras_calibration stereo): pixels, metres; std = 1 sigma.\n'
                % (left_file, right_file))
        yaml.safe_dump(report(res), f, default_flow_style=None, sort_keys=False)
    # OpenCV: p_right = R p_left + T, i.e. [R|T] = T_right_left.
    entry = frame_entry(left_frame, right_frame, inverse(make_transform(res.R, res.T)))
    save_world_frames(os.path.join(output_dir, EXTRINSICS_FILE), [entry])
    return entry
