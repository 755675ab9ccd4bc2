1;  % script file: Octave side of bench/runtime_compare.sh (issue 3 §7)
% usage: octave --no-gui -q bench/octave/runtime_compare.m DIR "10 50 200 1000" [polyeig]
% DIR/chain_<n>/{M,Q,K,g_ref}.mtx are written by `runtime_bench --write-matrices DIR`.
% Prints CSV lines: octave,<benchmark>,<n>,<seconds per frequency or per call>,<max rel err>

% read_mm: the Matrix Market reader shared with the peer scripts (bench/peers/read_mm.m).
addpath(fullfile(fileparts(mfilename('fullpath')), '..', 'peers'));

args = argv();
dir = args{1};
sizes = str2num(args{2});
do_polyeig = numel(args) > 2 && strcmp(args{3}, 'polyeig');
pkg load control
f = 100 * 200 .^ ((0:999) / 999);
w = 2 * pi * f;
for n = sizes
  d = sprintf('%s/chain_%d', dir, n);
  Ms = read_mm([d '/M.mtx']); Qs = read_mm([d '/Q.mtx']); Ks = read_mm([d '/K.mtx']);
  G = read_mm([d '/g_ref.mtx']); gref = G(:, 1) + 1i * G(:, 2);
  M = full(Ms); Q = full(Qs); K = full(Ks);
  e1 = zeros(n, 1); e1(1) = 1;
  % freqresp on the state-space model (A formed with M\, as a user would)
  if n <= 50
    idx = 1:1000;
  elseif n <= 200
    idx = 1:10:1000;
  else
    idx = 1:100:1000;
  end
  A = [zeros(n) eye(n); -(M \ K) -(M \ Q)];
  B = [zeros(n, 1); M \ e1];
  C = [1 zeros(1, 2 * n - 1)];
  sys = ss(A, B, C, 0);
  tic; H = freqresp(sys, w(idx)); t = toc;
  H = H(:);
  err = max(abs(H - gref(idx)) ./ abs(gref(idx)));
  printf('octave,freqresp,%d,%.6g,%.3g\n', n, t / numel(idx), err);
  % a plain loop of sparse solves
  b = sparse(e1);
  h = zeros(1000, 1);
  tic;
  for k = 1:1000
    y = (Ks - w(k)^2 * Ms + 1i * w(k) * Qs) \ b;
    h(k) = y(1);
  end
  t = toc;
  err = max(abs(h - gref) ./ abs(gref));
  printf('octave,sparse_loop,%d,%.6g,%.3g\n', n, t / 1000, err);
  if do_polyeig && n >= 200
    tic; [X, e] = polyeig(K, Q, M); t = toc;
    printf('octave,polyeig_with_vectors,%d,%.6g,nan\n', n, t);
  end
  fflush(stdout);
end
