#include "perinox/model/Model.hpp"

#include <cmath>
#include <sstream>

#include "Effects.hpp"

namespace perinox {

template <int D>
typename BondWork<D>::Vec BondWork<D>::g(int k) const {
  if (k == 0) return -gsum;
  return Vj[k - 1] * h[k - 1];
}

double micromodulusC(const MaterialSpec& m, double delta, double thickness) {
  const double pi = 3.14159265358979323846;
  switch (m.dim) {
    case 1:
      return 2.0 * m.E / (thickness * delta * delta * delta);
    case 2: {
      const double kp = m.planar == PlanarMode::PlaneStress ? m.E / (2.0 * (1.0 - m.nu))
                                                           : m.E / (2.0 * (1.0 - m.nu - 2.0 * m.nu * m.nu));
      return 12.0 * kp / (pi * thickness * std::pow(delta, 4));
    }
    default: {
      const double k = m.E / (3.0 * (1.0 - 2.0 * m.nu));
      return 18.0 * k / (pi * std::pow(delta, 5));
    }
  }
}

struct Model::Impl {
  virtual ~Impl() = default;
  virtual void evaluate(const Model& m, const std::vector<double>& u, ElementSink& sink,
                        bool tangent) const = 0;
  virtual std::vector<ParticleOutput> outputs(const Model& m, const std::vector<double>& u) const = 0;
  virtual void add(const Material& mat, bool correspondence, const StabilizationSpec* stab) = 0;
  virtual std::vector<std::string> names() const = 0;
  virtual void prepare(const LocalParticles& p) = 0;
};

namespace {

template <int D>
struct ImplD final : Model::Impl {
  using Vec = Eigen::Matrix<double, D, 1>;
  using Mat = Eigen::Matrix<double, D, D>;
  std::vector<std::unique_ptr<ForceEffect<D>>> effects;

  void add(const Material& mat, bool correspondence, const StabilizationSpec* stab) override {
    if (correspondence) effects.push_back(std::make_unique<CorrespondenceEffect<D>>(mat));
    if (stab) effects.push_back(std::make_unique<StabilizationEffect<D>>(*stab));
  }
  std::vector<std::string> names() const override {
    std::vector<std::string> n;
    for (const auto& e : effects) n.push_back(e->name());
    return n;
  }
  void prepare(const LocalParticles& p) override {
    for (auto& e : effects) e->prepare(p);
  }

  /// Fills the kinematics of particle i: bonds, K, K^-1, F, h_j.
  static void kinematics(const LocalParticles& p, const std::vector<double>& u, int i,
                         BondWork<D>& w) {
    const auto b = p.famOffset[i];
    w.i = i;
    w.m = static_cast<int>(p.famOffset[i + 1] - b);
    w.nbr = p.famIndex.data() + b;
    w.Vi = p.volume[i];
    w.xi.resize(w.m);
    w.Y.resize(w.m);
    w.h.resize(w.m);
    w.Vj.resize(w.m);
    w.t.assign(w.m, Vec::Zero());
    Vec ui;
    for (int a = 0; a < D; ++a) ui[a] = u[i * D + a];
    w.K.setZero();
    Mat FK = Mat::Zero();
    for (int l = 0; l < w.m; ++l) {
      const int j = w.nbr[l];
      for (int a = 0; a < D; ++a) {
        w.xi[l][a] = p.X[j][a] - p.X[i][a];
        w.Y[l][a] = w.xi[l][a] + u[j * D + a] - ui[a];
      }
      w.Vj[l] = p.volume[j];
      w.K.noalias() += w.Vj[l] * w.xi[l] * w.xi[l].transpose();
      FK.noalias() += w.Vj[l] * w.Y[l] * w.xi[l].transpose();
    }
    w.Kinv = w.K.inverse();
    w.F = FK * w.Kinv;
    w.gsum.setZero();
    for (int l = 0; l < w.m; ++l) {
      w.h[l] = w.Kinv * w.xi[l];
      w.gsum += w.Vj[l] * w.h[l];
    }
  }

  void evaluate(const Model& model, const std::vector<double>& u, ElementSink& sink,
                bool tangent) const override {
    const LocalParticles& p = model.particles();
    BondWork<D> w;
    std::vector<int> parts;
    std::vector<double> r, K;
    for (int i = 0; i < p.numOwned; ++i) {
      kinematics(p, u, i, w);
      const int m = w.m;
      if (tangent) w.tan.assign(static_cast<std::size_t>(m) * (m + 1), Mat::Zero());
      for (const auto& e : effects) e->addForces(w, tangent);

      const int n = m + 1;
      parts.resize(n);
      parts[0] = i;
      for (int l = 0; l < m; ++l) parts[l + 1] = w.nbr[l];
      r.assign(static_cast<std::size_t>(n) * D, 0.0);
      for (int l = 0; l < m; ++l) {
        const double s = w.Vi * w.Vj[l];
        for (int a = 0; a < D; ++a) {
          r[a] -= s * w.t[l][a];
          r[(l + 1) * D + a] += s * w.t[l][a];
        }
      }
      if (tangent) {
        const int nd = n * D;
        K.assign(static_cast<std::size_t>(nd) * nd, 0.0);
        for (int l = 0; l < m; ++l) {
          const double s = w.Vi * w.Vj[l];
          for (int k = 0; k < n; ++k) {
            const Mat& B = w.dT(l, k);
            for (int a = 0; a < D; ++a)
              for (int c = 0; c < D; ++c) {
                const double v = s * B(a, c);
                K[static_cast<std::size_t>(a) * nd + k * D + c] -= v;
                K[static_cast<std::size_t>((l + 1) * D + a) * nd + k * D + c] += v;
              }
          }
        }
      }
      sink.add(parts.data(), n, r.data(), tangent ? K.data() : nullptr);
    }
  }

  std::vector<ParticleOutput> outputs(const Model& model, const std::vector<double>& u) const override {
    const LocalParticles& p = model.particles();
    std::vector<ParticleOutput> out(p.numOwned);
    BondWork<D> w;
    for (int i = 0; i < p.numOwned; ++i) {
      kinematics(p, u, i, w);
      Mat F = w.F;
      Eigen::Matrix3d s;
      out[i].F.setIdentity();
      out[i].F.template topLeftCorner<D, D>() = F;
      if (!model.material().template cauchy<D>(F, s)) s.setConstant(std::nan(""));
      out[i].cauchy = s;
    }
    return out;
  }
};

}  // namespace

Model::Model(const MaterialSpec& material, LocalParticles particles)
    : materialSpec_(material), material_(material), particles_(std::move(particles)) {
  switch (particles_.dim) {
    case 1: impl_ = std::make_unique<ImplD<1>>(); break;
    case 2: impl_ = std::make_unique<ImplD<2>>(); break;
    case 3: impl_ = std::make_unique<ImplD<3>>(); break;
    default: throw std::invalid_argument("model dimension must be 1, 2 or 3");
  }
  if (material.dim != particles_.dim)
    throw std::invalid_argument("material dimension differs from the discretisation's");
  checkShapeTensors();
}

Model::~Model() = default;

void Model::enableCorrespondence() { impl_->add(material_, true, nullptr); impl_->prepare(particles_); }
void Model::enableStabilization(const StabilizationSpec& s) { impl_->add(material_, false, &s); impl_->prepare(particles_); }
std::vector<std::string> Model::effectNames() const { return impl_->names(); }

void Model::evaluate(const std::vector<double>& u, ElementSink& sink, bool wantTangent) const {
  impl_->evaluate(*this, u, sink, wantTangent);
}

std::vector<ParticleOutput> Model::outputs(const std::vector<double>& u) const {
  return impl_->outputs(*this, u);
}

void Model::checkShapeTensors() const {
  // A shape tensor must be invertible: the family has to span the space. Measure conditioning
  // relative to the family's own scale so the check is unit-free.
  const int D = particles_.dim;
  for (int i = 0; i < particles_.numOwned; ++i) {
    Eigen::Matrix3d K = Eigen::Matrix3d::Zero();
    double scale = 0;
    for (auto p = particles_.famOffset[i]; p < particles_.famOffset[i + 1]; ++p) {
      const int j = particles_.famIndex[p];
      Eigen::Vector3d xi = particles_.X[j] - particles_.X[i];
      K += particles_.volume[j] * xi * xi.transpose();
      scale += particles_.volume[j] * xi.squaredNorm();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K.topLeftCorner(D, D));
    const double minEig = es.eigenvalues().minCoeff();
    if (!(scale > 0) || minEig <= 1e-10 * scale) {
      std::ostringstream s;
      s << "particle " << particles_.globalId[i] << " has a singular shape tensor (family of "
        << (particles_.famOffset[i + 1] - particles_.famOffset[i])
        << " bonds does not span the space); it must be detached or the horizon enlarged";
      throw EvaluationError(s.str(), particles_.globalId[i]);
    }
  }
}

template struct BondWork<1>;
template struct BondWork<2>;
template struct BondWork<3>;

}  // namespace perinox
