// Independent Newton-Euler model of the Panda written for cross-checking only
// (not pumasim's code: it shares nothing with models/). Parameters typed from the supplementary material
// Tables VIII/IX (RA-L 2019 Gaz et al.), kinematics = Craig modified DH.
#pragma once
#include <Eigen/Dense>
#include <cmath>

namespace indep {
using Eigen::Matrix3d; using Eigen::Vector3d;
typedef Eigen::Matrix<double,7,1> V7; typedef Eigen::Matrix<double,7,7> M7;

static const double A_[7]     = {0, 0, 0, 0.0825, -0.0825, 0, 0.088};   // a_{i-1}
static const double D_[7]     = {0.333, 0, 0.316, 0, 0.384, 0, 0};      // d_i
static const double AL_[7]    = {0, -M_PI/2, M_PI/2, M_PI/2, -M_PI/2, M_PI/2, M_PI/2}; // alpha_{i-1}
static const double MASS[7]   = {4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 7.35522e-01};
static const double COM[7][3] = {{3.875e-03, 2.081e-03, 0 /* c1z "don't care" */},
  {-3.141e-03, -2.872e-02, 3.495e-03}, {2.7518e-02, 3.9252e-02, -6.6502e-02},
  {-5.317e-02, 1.04419e-01, 2.7454e-02}, {-1.1953e-02, 4.1065e-02, -3.8437e-02},
  {6.0149e-02, -1.4117e-02, -1.0517e-02}, {1.0517e-02, -4.252e-03, 6.1597e-02}};
// Ixx Ixy Ixz Iyy Iyz Izz about the COM, axes parallel to link frame i
static const double IN[7][6]  = {
  {7.0337e-01, -1.3900e-04, 6.7720e-03, 7.0661e-01, 1.9169e-02, 9.1170e-03},
  {7.9620e-03, -3.9250e-03, 1.0254e-02, 2.8110e-02, 7.0400e-04, 2.5995e-02},
  {3.7242e-02, -4.7610e-03, -1.1396e-02, 3.6155e-02, -1.2805e-02, 1.0830e-02},
  {2.5853e-02, 7.7960e-03, -1.3320e-03, 1.9552e-02, 8.6410e-03, 2.8323e-02},
  {3.5549e-02, -2.1170e-03, -4.0370e-03, 2.9474e-02, 2.2900e-04, 8.6270e-03},
  {1.9640e-03, 1.0900e-04, -1.1580e-03, 4.3540e-03, 3.4100e-04, 5.4330e-03},
  {1.2516e-02, -4.2800e-04, -1.1960e-03, 1.0027e-02, -7.4100e-04, 4.8150e-03}};

struct Model {
  double mass[7]; Vector3d c[7]; Matrix3d Ic[7];
  double inertia_scale = 1.0;  // 1: tensors about COM (as documented)
  bool inertia_about_origin = false; // true: treat IN as about link origin (test hypothesis)
  Model() {
    for (int i=0;i<7;i++){ mass[i]=MASS[i]; c[i]=Vector3d(COM[i][0],COM[i][1],COM[i][2]);
      const double*p=IN[i]; Ic[i]<<p[0],p[1],p[2], p[1],p[3],p[4], p[2],p[4],p[5]; }
  }
  // R_{i-1,i}, p_{i-1,i} for modified DH
  static void tf(int i, double q, Matrix3d&R, Vector3d&p){
    double ca=cos(AL_[i]), sa=sin(AL_[i]), ct=cos(q), st=sin(q);
    R << ct, -st, 0,  st*ca, ct*ca, -sa,  st*sa, ct*sa, ca;
    p << A_[i], -sa*D_[i], ca*D_[i];
  }
  Matrix3d Icom(int i) const {
    if(!inertia_about_origin) return Ic[i];
    Vector3d r=c[i]; return Ic[i] - mass[i]*(r.dot(r)*Matrix3d::Identity() - r*r.transpose());
  }
  // RNEA: tau = M qdd + c(q,qd) + g(q); base gravity vector grav (world frame = frame 0)
  V7 rnea(const V7&q,const V7&qd,const V7&qdd,const Vector3d&grav) const {
    Vector3d w=Vector3d::Zero(), wd=Vector3d::Zero(), vd=-grav; // frame 0
    Matrix3d R[7]; Vector3d p[7], F[7], N[7]; const Vector3d z(0,0,1);
    for(int i=0;i<7;i++){
      tf(i,q(i),R[i],p[i]); Matrix3d Rt=R[i].transpose();
      Vector3d w_n = Rt*w + qd(i)*z;
      Vector3d wd_n = Rt*wd + (Rt*w).cross(qd(i)*z) + qdd(i)*z;
      Vector3d vd_n = Rt*(wd.cross(p[i]) + w.cross(w.cross(p[i])) + vd);
      w=w_n; wd=wd_n; vd=vd_n;
      Vector3d vdc = wd.cross(c[i]) + w.cross(w.cross(c[i])) + vd;
      Matrix3d I=Icom(i);
      F[i]=mass[i]*vdc; N[i]=I*wd + w.cross(I*w);
    }
    V7 tau; Vector3d f=Vector3d::Zero(), n=Vector3d::Zero();
    for(int i=6;i>=0;i--){
      Vector3d fn, nn;
      if(i==6){ fn=F[i]; nn=N[i] + c[i].cross(F[i]); }
      else { fn=R[i+1]*f + F[i]; nn=N[i] + R[i+1]*n + c[i].cross(F[i]) + p[i+1].cross(R[i+1]*f); }
      f=fn; n=nn; tau(i)=n.dot(z);
    }
    return tau;
  }
  M7 mass_matrix(const V7&q) const { M7 M; V7 z=V7::Zero();
    for(int j=0;j<7;j++){ V7 e=V7::Zero(); e(j)=1; M.col(j)=rnea(q,z,e,Vector3d::Zero()); } return M; }
  V7 gravity(const V7&q,double g0) const { V7 z=V7::Zero(); return rnea(q,z,z,Vector3d(0,0,-g0)); }
  V7 coriolis_vec(const V7&q,const V7&qd) const { V7 z=V7::Zero(); return rnea(q,qd,z,Vector3d::Zero()); }
};
}
