"""Boom-crane regressor Y(q, qd, qdd) of 002 eq. 4.1-4.2 - GENERATED, do not edit.

Written by ``python -m cablelab.plants.crane.symbolic`` from the energies of 002 eq. A.3-A.4
(Euler-Lagrange, eq. A.6). tau = Y @ pi with pi = I_tot, lb2_mb, lb2_m, lb_m, m, lb_mb, I_b, lc2_mc, lc_mc.
"""
import numpy as np

PARAM_GROUPS = ('I_tot', 'lb2_mb', 'lb2_m', 'lb_m', 'm', 'lb_mb', 'I_b', 'lc2_mc', 'lc_mc')


def regressor(q, qd, qdd, g=9.81):
    """(N, 5, 9) regressor; q, qd, qdd are (N, 5) [alpha, beta, d, theta1, theta2] (rad, m)."""
    q = np.asarray(q, dtype=float)
    qd = np.asarray(qd, dtype=float)
    qdd = np.asarray(qdd, dtype=float)
    n = q.shape[0]
    alpha_d = qd[:, 0]
    alpha_dd = qdd[:, 0]
    beta_d = qd[:, 1]
    beta_dd = qdd[:, 1]
    d = q[:, 2]
    d_d = qd[:, 2]
    d_dd = qdd[:, 2]
    theta1_d = qd[:, 3]
    theta1_dd = qdd[:, 3]
    theta2_d = qd[:, 4]
    theta2_dd = qdd[:, 4]
    c_beta = np.cos(q[:, 1])
    s_beta = np.sin(q[:, 1])
    c_theta1 = np.cos(q[:, 3])
    s_theta1 = np.sin(q[:, 3])
    c_theta2 = np.cos(q[:, 4])
    s_theta2 = np.sin(q[:, 4])
    x0 = c_beta**2
    x1 = alpha_d*c_beta
    x2 = beta_d*s_beta
    x3 = x1*x2
    x4 = alpha_dd*x0 - 2*x3
    x5 = c_beta*d_dd
    x6 = c_theta2*s_theta1
    x7 = 2*s_theta2
    x8 = d_d*x7
    x9 = alpha_dd*c_beta*d
    x10 = beta_dd*s_beta
    x11 = d*x6
    x12 = c_theta1*c_theta2
    x13 = c_beta*x12
    x14 = s_beta*s_theta2
    x15 = d*x14
    x16 = 2*alpha_d
    x17 = x15*x16
    x18 = c_theta2*d
    x19 = 2*theta2_d
    x20 = 2*d_d
    x21 = theta1_d*x20
    x22 = s_theta1*s_theta2
    x23 = c_beta*d
    x24 = theta2_dd*x23
    x25 = s_theta1*theta2_d
    x26 = beta_d**2
    x27 = c_beta*x26
    x28 = c_theta1*s_theta2
    x29 = theta1_d*x19
    x30 = theta1_d**2
    x31 = d*x30
    x32 = c_beta*x6
    x33 = theta2_d**2
    x34 = d*x33
    x35 = s_theta2**2
    x36 = d**2
    x37 = alpha_dd*x36
    x38 = x35*x37
    x39 = d*x35
    x40 = x20*x39
    x41 = alpha_d*x40
    x42 = theta1_dd*x36
    x43 = s_theta2*x12
    x44 = d*x12
    x45 = theta1_d*x44
    x46 = s_theta2*x36
    x47 = c_theta2*x46
    x48 = theta2_d*x16
    x49 = x47*x48
    x50 = c_theta2**2
    x51 = s_theta1*x50
    x52 = theta2_d*x20
    x53 = d*x52
    x54 = theta2_dd*x36
    x55 = x50*x54
    x56 = x35*x54
    x57 = s_theta1**2
    x58 = x50*x57
    x59 = d*x58
    x60 = alpha_d*x20
    x61 = c_theta1*x36
    x62 = theta1_d*x61
    x63 = x51*x61
    x64 = theta1_d*x16
    x65 = beta_dd*x0
    x66 = beta_dd*s_beta**2
    x67 = alpha_d**2
    x68 = c_beta*x67
    x69 = s_beta*x68
    x70 = x65 + x66 + x69
    x71 = c_beta*g
    x72 = theta2_dd*x18
    x73 = c_theta2*theta2_d
    x74 = s_beta*x20
    x75 = x16*x2
    x76 = c_theta1**2
    x77 = s_theta2*x72
    x78 = x73*x8
    x79 = x50*x76
    x80 = d*g
    x81 = x29*x47
    x82 = d_dd*s_theta2*x18
    x83 = x47*x67
    x84 = x33*x47
    x85 = theta2_d*x40
    x86 = x30*x47
    Y = np.zeros((n, 5, 9))
    Y[:, 0, 0] = alpha_dd
    Y[:, 0, 1] = (1/4)*alpha_dd*x0 - 1/2*x3
    Y[:, 0, 2] = x4
    Y[:, 0, 3] = -beta_d*x17 - c_beta*x25*x8 + d*theta1_dd*x13 + x1*x18*x19 + x1*x8 + x10*x11 + x11*x27 + x13*x21 - x22*x24 - x23*x28*x29 - x31*x32 - x32*x34 + x5*x6 + x7*x9
    Y[:, 0, 4] = -s_theta1*x55 - s_theta1*x56 - x19*x35*x62 - x25*x40 - x30*x46*x6 + x37*x58 + x38 + x41 + x42*x43 + x45*x8 - x49*x57 + x49 - x51*x53 + x59*x60 + x63*x64
    Y[:, 0, 7] = x4
    Y[:, 1, 1] = (1/4)*x65 + (1/4)*x66 + (1/4)*x69
    Y[:, 1, 2] = x70
    Y[:, 1, 3] = alpha_d*x6*x74 + alpha_dd*s_beta*x11 + c_beta*theta1_dd*x11 + c_beta*x28*x52 - d_dd*x14 + s_beta*x44*x64 - s_beta*x72 - theta1_d*x23*x25*x7 - x12*x5 + x13*x31 + x13*x34 + x15*x33 + x15*x67 - x17*x25 + x21*x32 + x24*x28 + x71 - x73*x74
    Y[:, 1, 5] = (1/2)*x71
    Y[:, 1, 6] = beta_dd
    Y[:, 1, 7] = x70
    Y[:, 1, 8] = -x71
    Y[:, 2, 3] = alpha_dd*c_beta*c_theta2*s_theta1 - beta_dd*x13 - beta_dd*x14 + c_theta1*c_theta2*s_beta*x26 - s_theta2*x27 - s_theta2*x68 - x6*x75
    Y[:, 2, 4] = 2*alpha_d*d*s_theta1*theta2_d*x35 + 2*alpha_d*d*s_theta1*theta2_d*x50 - alpha_d*x45*x7 + c_theta2*d*s_theta2*theta2_dd + 2*c_theta2*d_d*s_theta2*theta2_d + d_dd*x35 + d_dd*x50*x57 + d_dd*x50*x76 - g*x12 - x30*x59 - x31*x79 - x33*x39 - x33*x59 - x34*x79 - x39*x67 - x57*x77 - x57*x78 - x59*x67 - x76*x77 - x76*x78
    Y[:, 3, 3] = alpha_dd*c_beta*c_theta1*c_theta2*d + beta_dd*c_beta*c_theta2*d*s_theta1 - s_beta*x11*x26 - x44*x75
    Y[:, 3, 4] = alpha_d*x44*x8 + d*x21*x79 + x21*x59 + x37*x43 + x42*x58 + x42*x79 + x48*x50*x61 - x57*x81 + x6*x80 - x63*x67 - x76*x81
    Y[:, 4, 3] = 2*alpha_d*beta_d*d*s_beta*s_theta1*s_theta2 + beta_dd*c_beta*c_theta1*d*s_theta2 - c_theta1*x15*x26 - x10*x18 - x18*x27 - x18*x68 - x22*x9
    Y[:, 4, 4] = -d*x51*x60 - s_theta1*x38 - s_theta1*x41 - x16*x50*x62 + x28*x80 - x37*x51 + x50*x53 + x55 + x56*x57 + x56*x76 - x57*x82 + x57*x83 + x57*x84 + x57*x85 + x57*x86 - x76*x82 + x76*x84 + x76*x85 + x76*x86 + x82 - x83 - x84
    return Y
